// The weaver subcommands.  Each returns the process exit status: 0 success,
// 1 failure (with a one-line message on stderr), 2 bad usage.
#pragma once

#include <string>
#include <vector>

#include "balance/balance.h"
#include "boundary/boundary.h"
#include "schema/status.h"
#include "util/args.h"
#include "util/memory_budget.h"

namespace weaver {
struct ConstructOptions;
struct ConstructPlan;
struct ConstructResult;
struct ExportOptions;
}  // namespace weaver

namespace weaver::cli {

int cmd_generate(int argc, char** argv);
int cmd_import(int argc, char** argv);
int cmd_construct(int argc, char** argv);
int cmd_balance(int argc, char** argv);
int cmd_extract(int argc, char** argv);
int cmd_export(int argc, char** argv);
int cmd_partition(int argc, char** argv);
int cmd_stat(int argc, char** argv);
int cmd_query(int argc, char** argv);
int cmd_shell(int argc, char** argv);
int cmd_slice(int argc, char** argv);
int cmd_verify(int argc, char** argv);
int cmd_recover(int argc, char** argv);
int cmd_compact(int argc, char** argv);
int cmd_aggregate(int argc, char** argv);
int cmd_boundary(int argc, char** argv);
// The boundary table's line, as 'weaver boundary' and 'weaver mesh' print it.
void print_boundary(const BoundaryResult& r, double secs);
int cmd_model(int argc, char** argv);
int cmd_serve(int argc, char** argv);

// Prints "weaver <command>: <message>" to stderr; returns 1 (2 for usage
// errors, which are InvalidArgument statuses raised while parsing).
int report(const std::string& command, const Status& st);
// The message report() prints for st.
std::string error_text(const Status& st);
int usage_error(const std::string& command, const std::string& message, const char* usage);

int cmd_mesh(int argc, char** argv);

// `construct`'s command line (cmd_construct's, and weaver-mpi's): DB and
// the options.  Returns -1 to go on, else the exit status (after --help's
// text, or a usage error).
int parse_construct_command(int argc, char** argv, std::string* db, weaver::ConstructOptions* o,
                            bool* quiet);
// The construct options and plan printout shared by `construct` and `mesh`.
Status parse_construct_options(const ParsedArgs& args, weaver::ConstructOptions* o);
// The plan's lines; db names the database to be written (its file
// system's free space is set against the estimate's disk).
void print_construct_plan(const weaver::ConstructOptions& o, const weaver::ConstructPlan& p,
                          const std::string& db);
// `export`'s options (weaver export's, and weaver-mpi's), DB aside.
Status parse_export_options(const ParsedArgs& args, weaver::ExportOptions* o);
// The "constructed ..." line of a finished construct that took secs.
void print_construct_result(const weaver::ConstructResult& r, double secs);
// The balanced construct's figures (nothing for --unbalanced).
void print_construct_balance(const weaver::ConstructResult& r);
// A --model naming a model file (etree:, grid:, layers:, xyz:): imported
// into DB's model table, printed, and read from there ("db:DB").
Status import_model_option(const std::string& db, weaver::ConstructOptions* o);

// A database with a model table and no mesh: a model database, whose
// queries (`material` only, in metres) 'weaver model material' answers;
// query_model runs one (memory: --memory's text, "" for the default).
bool is_model_only(const std::string& db);
// A database about to be written by a writer of mesh (mesh = true) or of a
// model database: InvalidArgument when db holds tables of the other kind
// (a model database given to mesh, a mesh given to model import).
Status check_target_kind(const std::string& db, bool mesh);
int query_model(const std::string& db, const std::vector<std::string>& words,
                const std::string& memory);

// --memory: at least MemoryBudget::kMinBytes and at most the machine's
// physical memory; MemoryBudget::kDefaultBytes when absent.
Status memory_option(const ParsedArgs& args, MemoryBudget* budget);
// --outside clamp|error: whether a point outside a model's box is an error
// (default: no, it takes the nearest model cell's values).
Status outside_option(const ParsedArgs& args, bool* error);
// The ground's options of construct, mesh and weaver-mpi, in their --help.
#define WEAVER_GROUND_USAGE                                                            \
  "  --surface SOURCE   the ground the mesh follows: flat (the default, a flat top;\n" \
  "                     an rfile model brings its own unless this says flat),\n"       \
  "                     rfile:FILE (its topography block) or asc:FILE (an ESRI\n"      \
  "                     ASCII raster: columns east = the mesh's y, rows north =\n"     \
  "                     its x, metres).  Air is never meshed; a leaf the ground\n"     \
  "                     crosses carries its solid fraction (column 'solid')\n"         \
  "  --surface-crs frame|lonlat  with --origin-geo: the raster in the frame's\n"       \
  "                     metres (default) or in degrees of longitude, latitude\n"       \
  "  --top-elevation E  elevation of z = 0, metres (default: the highest ground,\n"    \
  "                     rounded up to a tick; 0 when flat); --domain's LZ counts\n"    \
  "                     down from it\n"                                                \
  "  --model-z depth|elevation  how the model reads z: depth below the local\n"        \
  "                     ground (default, but for an rfile) or down from sea level\n"   \
  "                     (an rfile's default)\n"                                        \
  "  --surface-edge M   split leaves the ground crosses down to this edge, metres\n"   \
  "                     (default: the wavelength rule alone, its samples in the air\n" \
  "                     taken at the ground below them)\n"
Status threads_option(const ParsedArgs& args, int default_threads, int* threads);
// --algorithm auto|windows|closure of balance (weaver's and weaver-mpi's).
Status balance_algorithm_option(const ParsedArgs& args, BalanceOptions::Algorithm* algorithm);
// --model db:PATH of balance: a model database the octant table's model may
// be in, besides DB itself (BalanceOptions::model_dirs).
Status balance_model_option(const ParsedArgs& args, std::vector<std::string>* model_dirs);
// The number of cores (at least 1): the default of every --threads.
int default_threads();

}  // namespace weaver::cli
