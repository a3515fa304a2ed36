#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli/cli.h"
#include "export/export.h"
#include "partition/partition.h"
#include "util/progress.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver partition DB --parts N [--method sfc|graph] [--weight none|level]\n"
    "                           [--compare] [--memory BYTES] [--quiet]\n"
    "\n"
    "Cuts the elements of DB's mesh into N parts and stores the partition with the\n"
    "database (a small table of runs of element ids), where 'weaver export --format\n"
    "raw|pvtu --parts N' finds it.  Prints, for each part, its elements, the nodes it\n"
    "owns (a node belongs to the lowest part using it), the nodes it shares with\n"
    "other parts, and the element faces it shares with other parts; then the edge\n"
    "cut (element pairs in different parts sharing a face, 2:1 faces included).\n"
    "  --method sfc     contiguous ranges of the Z-order (element ids), balanced by\n"
    "                   --weight (default; fast, and each part is a compact region)\n"
    "  --method graph   METIS: the face dual graph (weaver export --format metis) run\n"
    "                   through gpmetis, which must be on the PATH (Debian: metis)\n"
    "  --weight level   sfc: weigh each element 2^(level - coarsest level), the cost of\n"
    "                   local time stepping (default none: every element 1)\n"
    "  --compare        also report the other method's partition (not stored)\n"
    "  --memory BYTES   memory budget (default 256M): the octant table's cache (a\n"
    "                   quarter, at most 64M), the node table's (a quarter), the\n"
    "                   partition table's (a sixteenth, at most 4M), the face\n"
    "                   neighbours' table leaves (an eighth, at most 8M) and the\n"
    "                   sort of (node, part) pairs of the report (the rest)\n"
    "  --quiet          no progress line on stderr\n";

// Runs gpmetis on the dual graph of db in dir; the part file's path.
Status run_gpmetis(const std::string& db, const std::string& dir, uint32_t parts,
                   const MemoryBudget& memory, std::string* part_file, std::string* edge_cut) {
  ExportOptions eo;
  eo.format = ExportFormat::kMetis;
  eo.out = dir + "/graph";
  eo.memory = memory;
  ExportResult er;
  WEAVER_RETURN_IF_ERROR(export_mesh(db, eo, &er));
  const std::string log = dir + "/gpmetis.log";
  const pid_t pid = ::fork();
  if (pid == 0) {
    FILE* out = std::freopen(log.c_str(), "w", stdout);
    (void)out;
    ::dup2(STDOUT_FILENO, STDERR_FILENO);
    const std::string n = std::to_string(parts);
    ::execlp("gpmetis", "gpmetis", eo.out.c_str(), n.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  int status = 0;
  if (pid < 0 || ::waitpid(pid, &status, 0) < 0) {
    return Status::IOError(std::string("cannot run gpmetis: ") + std::strerror(errno));
  }
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  if (!WIFEXITED(status) || WEXITSTATUS(status) == 127) {
    return Status::NotFound("gpmetis is not on the PATH (Debian: apt install metis)");
  }
  if (WEXITSTATUS(status) != 0) {
    return Status::IOError("gpmetis failed: " + text.substr(0, text.find('\n', 200)));
  }
  // gpmetis prints " - Edgecut: 279, communication volume: ..."
  const size_t at = text.find("Edgecut:");
  if (at != std::string::npos) {
    const size_t digits = text.find_first_of("0123456789", at);
    if (digits != std::string::npos) {
      *edge_cut = text.substr(digits, text.find_first_not_of("0123456789", digits) - digits);
    }
  }
  *part_file = eo.out + ".part." + std::to_string(parts);
  return Status::Ok();
}

void print_report(const char* title, const PartitionReport& r) {
  std::printf("%s\n%6s %12s %14s %12s %12s %10s\n", title, "part", "elements", "weight",
              "owned nodes", "shared nodes", "cut faces");
  PartStats sum;
  uint64_t most = 0;
  for (size_t p = 0; p < r.parts.size(); ++p) {
    const PartStats& s = r.parts[p];
    if (r.parts.size() <= 64) {
      std::printf("%6zu %12llu %14llu %12llu %12llu %10llu\n", p, (unsigned long long)s.elements,
                  (unsigned long long)s.weight, (unsigned long long)s.owned_nodes,
                  (unsigned long long)s.shared_nodes, (unsigned long long)s.cut_faces);
    }
    sum.elements += s.elements, sum.weight += s.weight, sum.owned_nodes += s.owned_nodes;
    sum.shared_nodes += s.shared_nodes, sum.cut_faces += s.cut_faces;
    most = std::max(most, s.elements);
  }
  std::printf("%6s %12llu %14llu %12llu %12llu %10llu\n", "all", (unsigned long long)sum.elements,
              (unsigned long long)sum.weight, (unsigned long long)sum.owned_nodes,
              (unsigned long long)sum.shared_nodes, (unsigned long long)sum.cut_faces);
  const double mean = double(sum.elements) / std::max<size_t>(1, r.parts.size());
  std::printf("edge cut %llu faces, %llu nodes shared, largest part %.3f x the mean\n",
              (unsigned long long)r.edge_cut, (unsigned long long)r.shared_nodes,
              mean > 0 ? most / mean : 0.0);
}

}  // namespace

int cmd_partition(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"parts", "method", "weight", "memory"},
                         {"compare", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("partition", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("partition", "expected one DB", kUsage);
  const std::string db = args.positional[0];
  PartitionOptions o;
  if (!args.values.count("parts")) return usage_error("partition", "--parts N is missing", kUsage);
  uint64_t parts = 0;
  st = parse_count(args.values["parts"], "--parts", &parts);
  if (st.ok() && (parts < 1 || parts > 1000000)) st = Status::InvalidArgument("--parts: 1 to 1M");
  if (!st.ok()) return usage_error("partition", st.message(), kUsage);
  o.parts = uint32_t(parts);
  const std::string method = args.values.count("method") ? args.values["method"] : "sfc";
  if (method != "sfc" && method != "graph") {
    return usage_error("partition", "--method is sfc or graph, not '" + method + "'", kUsage);
  }
  o.method = method == "sfc" ? PartitionOptions::Method::kSfc : PartitionOptions::Method::kGraph;
  const std::string weight = args.values.count("weight") ? args.values["weight"] : "none";
  if (weight != "none" && weight != "level") {
    return usage_error("partition", "--weight is none or level, not '" + weight + "'", kUsage);
  }
  o.weight = weight == "none" ? PartitionOptions::Weight::kNone : PartitionOptions::Weight::kLevel;
  st = memory_option(args, &o.memory);
  if (!st.ok()) return usage_error("partition", st.message(), kUsage);
  const bool compare = args.flags.count("compare") != 0;
  const auto t0 = std::chrono::steady_clock::now();
  ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "partition",
                    "elements");
  o.progress = line.fn();

  // The graph method's scratch: the dual graph and gpmetis's files.
  const std::string scratch = db + ".partition-tmp";
  std::string metis_cut;
  auto graph_partition = [&](PartitionOptions g, PartitionReport* r) {
    std::error_code ec;
    std::filesystem::create_directories(scratch, ec);
    g.method = PartitionOptions::Method::kGraph;
    Status s = run_gpmetis(db, scratch, g.parts, g.memory, &g.part_file, &metis_cut);
    if (s.ok()) s = partition_mesh(db, g, r);
    std::filesystem::remove_all(scratch, ec);
    return s;
  };
  PartitionReport stored, other;
  if (o.method == PartitionOptions::Method::kGraph) {
    st = graph_partition(o, &stored);
    if (st.ok() && compare) {
      PartitionOptions s = o;
      s.method = PartitionOptions::Method::kSfc;
      s.store = false;
      st = partition_mesh(db, s, &other);
    }
  } else {
    // The graph partition, if compared, is stored first, then replaced by the sfc one.
    if (compare) st = graph_partition(o, &other);
    if (st.ok()) st = partition_mesh(db, o, &stored);
  }
  line.finish();
  if (!st.ok()) return report("partition", st);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string title = "partition: " + std::to_string(o.parts) + " parts by " + method +
                            (method == "sfc" ? " (weight " + weight + ")" : "") + ", " +
                            std::to_string(stored.runs) + " runs stored";
  print_report(title.c_str(), stored);
  if (compare) {
    const std::string t = std::string("\ncompared (not stored): ") +
                          (method == "sfc" ? "graph (gpmetis)" : "sfc (weight " + weight + ")");
    print_report(t.c_str(), other);
  }
  if (!metis_cut.empty()) std::printf("gpmetis reported an edge cut of %s\n", metis_cut.c_str());
  std::printf("in %.2fs\n", secs);
  return 0;
}

}  // namespace weaver::cli
