// weaver: an embedded mesh database for octree hexahedral meshes.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <system_error>

#include "cli/cli.h"

namespace {

constexpr char kUsage[] =
    "usage: weaver <command> [arguments]\n"
    "\n"
    "commands:\n"
    "  generate FILE     write a sample octree as octant text\n"
    "  mesh DB           construct, balance and extract in one go\n"
    "  construct DB      build the octant table from a velocity model\n"
    "  balance DB        2:1 balance the octant table (minimal refinement)\n"
    "  import DB         load octant text into the octant table of database DB\n"
    "  extract DB        extract the mesh nodes of a balanced octree\n"
    "  export DB         write the mesh for ParaView, Gmsh, METIS, numpy or as CSV\n"
    "  partition DB      cut the elements into parts (space-filling curve or METIS)\n"
    "  stat DB           table sizes, per-level counts and storage overhead\n"
    "  query DB ...      what is at a point (or a file of them), an element, a node,\n"
    "                    their neighbours, with material\n"
    "  shell DB          an interactive prompt for queries over one open database\n"
    "  slice DB          a picture (PNG or SVG) of the mesh cut by a plane\n"
    "  aggregate DB      summarise the elements of coarse octants (for serve's maps)\n"
    "  boundary DB       the faces a solver treats as boundaries (mesh builds them)\n"
    "  serve DB          explore the mesh in a browser, and query it over HTTP\n"
    "  verify DB         check pages, keys and the mesh invariants\n"
    "  recover DB        rebuild a lost or damaged MANIFEST from the table files\n"
    "  compact DB        join the shards of weaver-mpi's tables into one file each\n"
    "  model import|material  a velocity model as a database (from etree or grid files)\n"
    "\n"
    "Run 'weaver <command> --help' for the arguments of one command, 'weaver\n"
    "--version' for the version.\n";

const char* g_command = "";  // for the out-of-memory line

// Running out of memory anywhere, on any thread, ends in one line and exit
// status 1.  A writer interrupted so leaves its last committed state (the
// same as a crash: see "Guarantees" in docs/storage.md).
[[noreturn]] void out_of_memory() {
  std::fprintf(stderr, "weaver %s: out of memory (try a smaller --memory)\n", g_command);
  std::fflush(stderr);
  std::_Exit(1);
}

[[noreturn]] void on_terminate() {
  if (const std::exception_ptr e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::bad_alloc&) {
      out_of_memory();
    } catch (const std::system_error& x) {
      // A thread the system would not start (no memory for its stack, or
      // too many threads): as plain as running out of memory.
      if (x.code() == std::errc::resource_unavailable_try_again) {
        std::fprintf(stderr, "weaver %s: cannot start a thread: %s (try fewer --threads)\n",
                     g_command, x.what());
        std::fflush(stderr);
        std::_Exit(1);
      }
      std::fprintf(stderr, "weaver %s: internal error: %s\n", g_command, x.what());
    } catch (const std::exception& x) {
      std::fprintf(stderr, "weaver %s: internal error: %s\n", g_command, x.what());
    } catch (...) {
      std::fprintf(stderr, "weaver %s: internal error\n", g_command);
    }
  }
  std::abort();
}

int dispatch(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  std::set_terminate(on_terminate);
  if (argc >= 2) g_command = argv[1];
  try {
    return dispatch(argc, argv);
  } catch (const std::bad_alloc&) {
    out_of_memory();
  }
}

namespace {

int dispatch(int argc, char** argv) {
  using namespace weaver::cli;
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    std::fputs(kUsage, argc < 2 ? stderr : stdout);
    return argc < 2 ? 2 : 0;
  }
  const std::string cmd = argv[1];
  if (cmd == "--version" || cmd == "version") {
    std::printf("weaver %s\n", WEAVER_VERSION);  // the project's version (CMakeLists.txt)
    return 0;
  }
  if (cmd == "generate") return cmd_generate(argc, argv);
  if (cmd == "import") return cmd_import(argc, argv);
  if (cmd == "construct") return cmd_construct(argc, argv);
  if (cmd == "mesh") return cmd_mesh(argc, argv);
  if (cmd == "balance") return cmd_balance(argc, argv);
  if (cmd == "extract") return cmd_extract(argc, argv);
  if (cmd == "export") return cmd_export(argc, argv);
  if (cmd == "partition") return cmd_partition(argc, argv);
  if (cmd == "stat") return cmd_stat(argc, argv);
  if (cmd == "query") return cmd_query(argc, argv);
  if (cmd == "shell") return cmd_shell(argc, argv);
  if (cmd == "slice") return cmd_slice(argc, argv);
  if (cmd == "serve") return cmd_serve(argc, argv);
  if (cmd == "verify") return cmd_verify(argc, argv);
  if (cmd == "recover") return cmd_recover(argc, argv);
  if (cmd == "compact") return cmd_compact(argc, argv);
  if (cmd == "aggregate") return cmd_aggregate(argc, argv);
  if (cmd == "boundary") return cmd_boundary(argc, argv);
  if (cmd == "model") return cmd_model(argc, argv);
  std::fprintf(stderr, "weaver: unknown command '%s'\n\n%s", cmd.c_str(), kUsage);
  return 2;
}

}  // namespace
