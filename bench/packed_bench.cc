// Packed against plain leaf pages on the tables of a real mesh.  Makes (or
// opens) a database with `weaver mesh`, reads its node and octant tables, and
// rebuilds each by sorted append in both formats: the node table (key + kind),
// the octant table (key + vp, vs, rho) and the octant keys alone.  For each:
// bytes per record (index included), build rate, full scans through the
// B+tree cursor with a small pool (pages come from the OS cache) and with the
// file in the pool (decode cost alone), and random gets.  Prints one JSON
// object per table and format (medians of --repeat runs), then a table with
// packed/plain ratios.
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "bench_util.h"
#include "db/database.h"
#include "db/node_table.h"
#include "db/octant_table.h"
#include "storage/btree.h"

namespace weaver::bench {
namespace {

struct Data {
  std::string name;
  TableOptions options;
  std::vector<uint64_t> keys;
  std::vector<std::byte> vals;
};

bool check(const Status& st, const char* what) {
  if (!st.ok()) std::fprintf(stderr, "packed_bench: %s: %s\n", what, st.to_string().c_str());
  return st.ok();
}

// Every record of a table, and its options with the payload fields kept or not.
bool load(Database& db, const char* table, const char* name, bool keys_only, Data* out) {
  std::unique_ptr<BTree> t;
  if (!check(db.open_table(table, 64 << 20, &t), table)) return false;
  out->name = name;
  out->options = t->options();
  out->options.metadata.clear();
  if (keys_only) out->options.schema = RecordSchema();
  const uint32_t p = out->options.schema.record_size();
  BTreeCursor c;
  if (!check(t->seek_cursor(0, &c), table)) return false;
  while (c.valid()) {
    out->keys.push_back(c.key());
    out->vals.insert(out->vals.end(), c.payload(), c.payload() + p);
    if (!check(c.next(), table)) return false;
  }
  return true;
}

std::unique_ptr<BTree> open_tree(const std::string& path, uint64_t pool) {
  std::unique_ptr<File> f;
  std::unique_ptr<BTree> t;
  if (!check(open_posix_file(path, OpenMode::kReadWrite, &f), path.c_str())) return nullptr;
  if (!check(BTree::open(std::move(f), pool, &t), path.c_str())) return nullptr;
  return t;
}

struct Run {
  double build_s = 0, scan_small_s = 0, scan_large_s = 0, get_s = 0;
  uint64_t bytes = 0, sum = 0;
};

// Sums keys and payload bytes, so that both formats can be checked to agree.
bool scan(BTree& t, double* secs, uint64_t* sum) {
  const double t0 = now_seconds();
  BTreeCursor c;
  uint64_t s = 0;
  if (!check(t.seek_cursor(0, &c), "seek")) return false;
  const uint32_t p = t.payload_size();
  while (c.valid()) {
    s += c.key();
    for (uint32_t i = 0; i < p; ++i) s += static_cast<uint64_t>(c.payload()[i]) << (i & 7);
    if (!check(c.next(), "next")) return false;
  }
  *secs = now_seconds() - t0;
  *sum = s;
  return true;
}

bool one_run(const Data& d, bool packed, const std::string& path, uint64_t queries, Run* r) {
  TableOptions o = d.options;
  o.packed = packed;
  {
    std::filesystem::remove(path);
    std::unique_ptr<File> f;
    std::unique_ptr<BTree> t;
    if (!check(open_posix_file(path, OpenMode::kCreateTruncate, &f), "create")) return false;
    if (!check(BTree::create(std::move(f), o, 8 << 20, &t), "create")) return false;
    const uint32_t p = o.schema.record_size();
    const double t0 = now_seconds();
    constexpr size_t kBatch = 1 << 16;
    for (size_t i = 0; i < d.keys.size(); i += kBatch) {
      const size_t n = std::min(kBatch, d.keys.size() - i);
      if (!check(t->append_batch(d.keys.data() + i, d.vals.data() + i * p, n), "append"))
        return false;
    }
    if (!check(t->commit(), "commit")) return false;
    r->build_s = now_seconds() - t0;
    r->bytes = t->file_bytes();
  }
  uint64_t sum2 = 0;
  {
    auto t = open_tree(path, 8 << 20);  // out of core: pages come through pread
    if (!t || !scan(*t, &r->scan_small_s, &r->sum)) return false;
  }
  auto t = open_tree(path, r->bytes + (16 << 20));  // in the pool: decoding alone
  double warm = 0;
  if (!t || !scan(*t, &warm, &sum2) || !scan(*t, &r->scan_large_s, &sum2)) return false;
  if (sum2 != r->sum) return std::fprintf(stderr, "packed_bench: scans disagree\n"), false;
  std::mt19937_64 rng(1);
  std::vector<std::byte> buf(o.schema.record_size() + 1);
  const double t0 = now_seconds();
  for (uint64_t q = 0; q < queries; ++q) {
    bool found = false;
    if (!check(t->get(d.keys[rng() % d.keys.size()], buf.data(), &found), "get")) return false;
    if (!found) return std::fprintf(stderr, "packed_bench: a key went missing\n"), false;
  }
  r->get_s = now_seconds() - t0;
  return true;
}

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver;
  using namespace weaver::bench;
  std::string dir = "/tmp/weaver-packed-bench", db_dir;
  std::string freq = "0.5";
  int repeat = 3;
  uint64_t queries = 1'000'000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--repeat" && i + 1 < argc)
      repeat = std::stoi(argv[++i]);
    else if (a == "--freq" && i + 1 < argc)
      freq = argv[++i];
    else if (a == "--db" && i + 1 < argc)
      db_dir = argv[++i];
    else if (a == "--dir" && i + 1 < argc)
      dir = argv[++i];
    else if (a == "--queries" && i + 1 < argc)
      queries = std::stoull(argv[++i]);
    else {
      std::printf(
          "usage: packed_bench [--freq F] [--db DB] [--repeat N] [--queries N] [--dir DIR]\n"
          "  --db DB    use this mesh database (default: weaver mesh --model basin --freq F\n"
          "             into DIR/mesh)\n");
      return 2;
    }
  }
  std::filesystem::create_directories(dir);
  if (db_dir.empty()) {
    db_dir = dir + "/mesh";
    std::filesystem::remove_all(db_dir);
    std::fprintf(stderr, "packed_bench: weaver mesh --model basin --freq %s ...\n", freq.c_str());
    if (run_program({WEAVER_BINARY, "mesh", db_dir, "--model", "basin", "--freq", freq}, nullptr)
            .empty()) {
      std::fprintf(stderr, "packed_bench: weaver mesh failed\n");
      return 1;
    }
  }
  std::vector<Data> data(3);
  {
    std::unique_ptr<Database> db;
    if (!check(Database::open(db_dir, Database::Mode::kRead, false, &db), db_dir.c_str())) return 1;
    if (!load(*db, kNodeTable, "nodes", false, &data[0]) ||
        !load(*db, kOctantTable, "octants", false, &data[1]) ||
        !load(*db, kOctantTable, "octant keys", true, &data[2])) {
      return 1;
    }
  }
  std::vector<std::map<std::string, std::string>> table;
  for (const Data& d : data) {
    const double n = static_cast<double>(d.keys.size());
    double plain_scan[2] = {0, 0}, plain_get = 0, plain_bytes = 0;
    uint64_t plain_sum = 0;
    for (const bool packed : {false, true}) {
      std::vector<double> build, small, large, get;
      Run r;
      for (int k = 0; k < repeat; ++k) {
        if (!one_run(d, packed, dir + "/table.bt", queries, &r)) return 1;
        build.push_back(n / r.build_s);
        small.push_back(n / r.scan_small_s);
        large.push_back(n / r.scan_large_s);
        get.push_back(queries / r.get_s);
      }
      if (!packed) plain_sum = r.sum;
      if (packed && r.sum != plain_sum) {
        std::fprintf(stderr, "packed_bench: %s: packed and plain tables differ\n", d.name.c_str());
        return 1;
      }
      const double bpr = r.bytes / n;
      Json j;
      j.add("table", d.name)
          .add("format", packed ? "packed" : "plain")
          .add("records", d.keys.size());
      j.add("schema", d.options.schema.to_text()).add("file_bytes", r.bytes);
      j.add("bytes_per_record", bpr).add("build_records_per_s", median(build));
      j.add("scan_8MiB_pool_records_per_s", median(small));
      j.add("scan_in_pool_records_per_s", median(large)).add("get_per_s", median(get));
      if (packed) {
        j.add("size_vs_plain", bpr / plain_bytes);
        j.add("scan_8MiB_pool_vs_plain", median(small) / plain_scan[0]);
        j.add("scan_in_pool_vs_plain", median(large) / plain_scan[1]);
        j.add("get_vs_plain", median(get) / plain_get);
      } else {
        plain_bytes = bpr;
        plain_scan[0] = median(small);
        plain_scan[1] = median(large);
        plain_get = median(get);
      }
      std::printf("%s\n", j.str().c_str());
      auto ratio = [&](const char* k) {
        return j.get(k).empty() ? "" : " (" + fmt(std::stod(j.get(k))) + "x)";
      };
      table.push_back(
          {{"table", d.name},
           {"format", packed ? "packed" : "plain"},
           {"B/record", fmt(bpr)},
           {"build rec/s", fmt(median(build))},
           {"scan rec/s, 8 MiB pool", fmt(median(small)) + ratio("scan_8MiB_pool_vs_plain")},
           {"scan rec/s, in pool", fmt(median(large)) + ratio("scan_in_pool_vs_plain")},
           {"get/s", fmt(median(get)) + ratio("get_vs_plain")}});
    }
  }
  std::printf("\nmedians of %d runs; tables of %s (records: nodes %zu, octants %zu)\n", repeat,
              db_dir.c_str(), data[0].keys.size(), data[1].keys.size());
  print_table(table, {"table", "format", "B/record", "build rec/s", "scan rec/s, 8 MiB pool",
                      "scan rec/s, in pool", "get/s"});
  std::filesystem::remove(dir + "/table.bt");
  return 0;
}
