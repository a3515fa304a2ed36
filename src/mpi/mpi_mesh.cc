// weaver-mpi mesh: construct (balanced as it descends) and extract on the
// ranks, each stage a sharded table (the commands' own code, one after the
// other); with --unbalanced, balance between them.
#include <cstdio>

#include "cli/cli.h"
#include "construct/construct.h"
#include "mpi/mpi_commands.h"

namespace weaver::mpi {

int mesh(const Comm& comm, int argc, char** argv) {
  // construct's arguments and --help (its usage names the other stages too).
  const int code = construct(comm, argc, argv);
  bool help = false;
  for (int i = 2; i < argc; ++i) help = help || std::string(argv[i]) == "--help";
  if (code != 0 || help) return code;
  std::string dir;
  ConstructOptions o;
  bool quiet = false;
  cli::parse_construct_command(argc, argv, &dir, &o, &quiet);
  if (!o.balanced) {
    BalanceOptions b;
    b.memory = o.memory;
    b.threads = o.threads;
    if (const int c = run_balance(comm, dir, b)) return c;
  }
  ExtractOptions x;
  x.memory = o.memory;
  x.threads = o.threads;
  x.packed = o.packed;
  return run_extract(comm, dir, x);
}

}  // namespace weaver::mpi
