#include <chrono>
#include <cstdio>

#include "boundary/boundary.h"
#include "cli/cli.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver boundary DB [--memory BYTES] [--threads N] [--plain] [--quiet]\n"
    "\n"
    "Builds the boundary table of DB ('weaver mesh' builds it as its last step):\n"
    "every element face, or quarter of a face, with no element across it, as\n"
    "(element id, face, part) and its kind: free surface (facing the air, or up\n"
    "on the domain's top) or domain side (x-, x+, y-, y+ or the bottom: where a\n"
    "solver absorbs).  Faces are numbered 0-5 as x-, x+, y-, y+, z- (up), z+\n"
    "(down); part 0 is the whole face, 1-4 the quarter (u, v) = ((part-1) & 1,\n"
    "(part-1) >> 1) of a face whose finer neighbours cover only some quarters,\n"
    "u and v its two in-plane axes in x, y, z order.  Exports carry it: raw's\n"
    "boundary_faces and boundary_kind, msh's physical groups free_surface and\n"
    "absorbing, vtu's NAME_boundary.vtu beside the mesh.  Replacing the octant\n"
    "table (a new mesh) drops it.\n"
    "\n"
    "  --memory BYTES   bounds the table caches and a carved mesh's surface,\n"
    "                   read again, and the records the threads past the first\n"
    "                   hold until their turn (default 256M)\n"
    "  --threads N      threads, each with an equal run of the elements (default:\n"
    "                   the number of cores); the same table for every N\n"
    "  --plain          plain leaf pages (default: packed)\n"
    "  --quiet          no progress line on stderr\n";

}  // namespace

void print_boundary(const BoundaryResult& r, double secs) {
  std::printf(
      "boundary   %llu faces (%llu quarters): %llu free surface, %llu domain sides; %s in "
      "%.2fs\n",
      (unsigned long long)r.faces, (unsigned long long)r.quarters,
      (unsigned long long)r.free_surface, (unsigned long long)(r.faces - r.free_surface),
      r.filled ? "the leaves fill their box"
               : ("neighbours looked up for " + std::to_string(r.asked) + " elements").c_str(),
      secs);
  if (r.least_dt > 0) {
    std::printf(
        "  time step  least edge / vp %.6g s, at element %llu (an explicit solver's step "
        "is a Courant number times it)\n",
        r.least_dt, (unsigned long long)r.least_dt_element);
  }
}

int cmd_boundary(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"memory", "threads"}, {"plain", "quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("boundary", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("boundary", "expected one DB", kUsage);
  BoundaryOptions o;
  o.packed = !args.flags.count("plain");
  st = memory_option(args, &o.memory);
  if (st.ok()) st = threads_option(args, default_threads(), &o.threads);
  if (!st.ok()) return usage_error("boundary", st.message(), kUsage);
  const auto t0 = std::chrono::steady_clock::now();
  BoundaryResult r;
  {
    ProgressLine line(ProgressLine::style_for_stderr(args.flags.count("quiet")), "boundary",
                      "elements");
    o.progress = line.fn();
    st = build_boundary(args.positional[0], o, &r);
  }
  if (!st.ok()) return report("boundary", st);
  print_boundary(r, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

}  // namespace weaver::cli
