// weaver-mpi mesh: construct (balanced as it descends), extract and the
// boundary on the ranks, each stage a sharded table (the commands' own code,
// one after the other), committed once: construct's shards (with
// --unbalanced, balance's in their place) and extract's are staged on rank
// 0's writer and go live with the boundary's, as weaver mesh commits, so a
// run killed or failing anywhere leaves the old database.
#include <cstdio>

#include "cli/cli.h"
#include "construct/construct.h"
#include "modeldb/open_model.h"
#include "mpi/mpi_commands.h"

namespace weaver::mpi {

int mesh(const Comm& comm, int argc, char** argv) {
  // construct's arguments and --help (its usage names the other stages too).
  std::string dir;
  ConstructOptions o;
  bool quiet = false;
  const int parsed = cli::parse_construct_command(argc, argv, &dir, &o, &quiet);
  if (parsed >= 0) return parsed;  // the help, or what is wrong
  StagedOctants staged;
  if (const int code = run_construct(comm, argc, argv, &staged)) return code;
  if (!o.balanced) {
    BalanceOptions b;
    b.memory = o.memory;
    b.threads = o.threads;
    b.staged_octants = staged.shards;
    if (names_model_database(o.model)) b.model_dirs.push_back(model_database_dir(o.model));
    if (const int c = run_balance(comm, dir, b, staged.db.get(), &staged.shards)) return c;
  }
  ExtractOptions x;
  x.memory = o.memory;
  x.threads = o.threads;
  x.packed = o.packed;
  x.staged_octants = staged.shards;
  x.stage = true;
  if (const int code = run_extract(comm, dir, x, staged.db.get())) return code;
  BoundaryOptions b;
  b.memory = o.memory;
  b.packed = o.packed;
  b.staged_octants = staged.shards;
  return run_boundary(comm, dir, b, staged.db.get(), true);
}

}  // namespace weaver::mpi
