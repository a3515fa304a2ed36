#include <malloc.h>

#include <csignal>
#include <cstdio>
#include <cstring>

#include "cli/cli.h"
#include "cli/point_batch.h"
#include "cli/serve_queries.h"
#include "serve/service.h"
#include "serve/streams.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver serve DB [--port P] [--bind ADDR] [--threads N] [--memory BYTES]\n"
    "                       [--allow-host NAME[,NAME...]] [--scratch DIR] [--quiet]\n"
    "\n"
    "Serves DB read-only over HTTP: a page to explore the mesh in a browser (a\n"
    "cross-section as a zoomable map of tiles, coloured by a field, the element\n"
    "under a click and its neighbours) and a JSON API with the answers of\n"
    "'weaver query --format json'.  Each request reads one committed state; a\n"
    "writer committing meanwhile is seen from the next request on.  With an\n"
    "aggregate table (weaver mesh makes one; 'weaver aggregate DB' for older\n"
    "meshes) a map pixel that holds many elements shows their least vs (or\n"
    "another summary) rather than the one at its centre.\n"
    "Safe to leave running: every value a client sends is parsed as a number,\n"
    "an id or a name from a fixed list (400 otherwise), never as an option or a\n"
    "path; a request whose Host is not this server's is 421, one from another\n"
    "site's page (Origin, Sec-Fetch-Site) 403.  Limits: 64 connections (more\n"
    "get 503), a request's head 40 KiB and body 64 MiB, a quarter of --memory\n"
    "for the bodies at once (503 past it), 10 s to send a request (408) or to\n"
    "wait for a thread (503), 5 s idle between two; a range lists at most 1M\n"
    "elements a page, a region at most 1M elements.  Answers past 1 MiB are sent\n"
    "as they are written (chunked), so the server stays within --memory; a\n"
    "client that reads an answer slowly holds a connection and spill space in\n"
    "DB (at most 1 GiB in all), not a thread, and one that reads slower than\n"
    "64 KB/s over 10 s is dropped.  Each request is logged on stderr.\n"
    "  --port P        the TCP port (default 8080; 0 for any free one)\n"
    "  --bind ADDR     the IPv4 address to listen on (default 127.0.0.1: this\n"
    "                  machine only; 0.0.0.0 for every interface)\n"
    "  --threads N     requests answered at once (default 4)\n"
    "  --memory BYTES  memory budget (default 256M): a quarter for request bodies,\n"
    "                  an eighth for the tables' leaf directories (built once,\n"
    "                  shared by the threads), a quarter for one large batch of\n"
    "                  points at a time, the rest for the threads' caches\n"
    "                  (a mesh of a billion elements answers fastest with 1G)\n"
    "  --allow-host NAMES  host names clients may address the server by (commas\n"
    "                  between), besides localhost, 127.0.0.1, [::1] and the\n"
    "                  bound address: a proxy's or the machine's own name\n"
    "  --scratch DIR   where a region's vtu is written before it is sent, and a\n"
    "                  slow reader's answer spilled (default: DB itself; give a\n"
    "                  directory for a database you may not write to)\n"
    "  --quiet         no line on stderr for each request\n"
    "Routes (GET and HEAD, but POST /api/points):\n"
    "  /                                  the page (and /page.css, /page.js)\n"
    "  /api/stat                          counts, units, extents, fields\n"
    "  /api/locate?x=&y=&z=[&units=m|ticks][&geo=1]\n"
    "  POST /api/points[?query=locate|material|node-at][&units=m]  lines or [[x,y,z],...]\n"
    "  /api/element/ID  /api/node/ID  /api/neighbors/ID[?kinds=all]\n"
    "  /api/node-elements/ID  /api/depends/ID\n"
    "  /api/range?box=X0,Y0,Z0,X1,Y1,Z1[&list=1[&limit=N][&from=ID]]  the count, or\n"
    "                                     a page of the elements and the next id\n"
    "  /api/section/AXIS/POSITION?color=F[&summary=S]  a section's extent and\n"
    "                                     colour range (S: min, max, mean, centre)\n"
    "  /api/tile/AXIS/POSITION/ZOOM/X/Y.png?color=F[&summary=S][&min=&max=]\n"
    "  /api/geo?x=&y=                     metres in the frame as lon, lat\n"
    "  /api/export.vtu?box=X0,Y0,Z0,X1,Y1,Z1  a region (metres) as weaver export writes it\n"
    "Example: weaver serve basin.db, then open http://127.0.0.1:8080/\n";

serve::Server* g_server = nullptr;

extern "C" void stop_serving(int) {
  if (g_server != nullptr) g_server->stop();
}

// --allow-host's names.
std::vector<std::string> allowed_hosts(const ParsedArgs& args) {
  std::vector<std::string> names;
  if (!args.values.count("allow-host")) return names;
  const std::string& list = args.values.at("allow-host");
  for (size_t from = 0; from <= list.size();) {
    size_t comma = list.find(',', from);
    if (comma == std::string::npos) comma = list.size();
    if (comma > from) names.push_back(list.substr(from, comma - from));
    from = comma + 1;
  }
  return names;
}

}  // namespace

int cmd_serve(int argc, char** argv) {
  ParsedArgs args;
  Status st =
      parse_args(argc, argv, 2, {"port", "bind", "threads", "memory", "allow-host", "scratch"},
                 {"quiet"}, &args);
  if (args.help) return std::fputs(kUsage, stdout), 0;
  if (!st.ok()) return usage_error("serve", st.message(), kUsage);
  if (args.positional.size() != 1) return usage_error("serve", "expected one DB", kUsage);
  serve::ServerOptions o;
  uint64_t port = uint64_t(o.port);
  if (args.values.count("port")) st = parse_u64(args.values.at("port"), "--port", &port);
  if (st.ok() && port > 65535) st = Status::InvalidArgument("--port is 0 to 65535");
  o.port = int(port);
  if (args.values.count("bind")) o.bind = args.values.at("bind");
  if (st.ok()) st = threads_option(args, 4, &o.threads);
  MemoryBudget memory;
  if (st.ok()) st = memory_option(args, &memory);
  if (!st.ok()) return usage_error("serve", st.message(), kUsage);
  const std::string& db = args.positional[0];
  // A quarter of the budget holds request bodies (at most 64 MiB each); an
  // eighth the tables' leaf directories, built once and shared by every
  // thread (at 2 Hz, 1.3B elements, the octant table's is 7 MB); a quarter
  // the batch lane, which one large batch of points at a time answers in
  // (Service); the rest is shared by the Explorers: one a worker, and the
  // helper that a batch of points borrows.  Answers are streamed
  // (serve/http.h), so they hold a megabyte or so each, whatever their size.
  o.max_buffered = std::max<uint64_t>(memory.bytes() / 4, 1 << 20);
  o.max_body = std::min(o.max_body, o.max_buffered);
  // A slow reader's spilled answer: an unnamed file in DB, or --scratch.
  o.scratch_dir = args.values.count("scratch") ? args.values.at("scratch") : db;
  o.log = !args.flags.count("quiet");
  const uint64_t directories = memory.bytes() / 8;
  const size_t lane_points = size_t(memory.bytes() / 4 / kBatchPointBytes);
  const MemoryBudget each(std::max<uint64_t>(memory.bytes() / 8 * 3 / uint64_t(o.threads + 1),
                                             MemoryBudget::kMinBytes));
  // Large blocks (a request's body, a batch's arrays) go back to the system
  // when freed: otherwise each thread's arena keeps the largest it has seen,
  // and the process outgrows --memory after a few batches.
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
  serve::Service service(db, each, directories, serve_query_runner(), lane_points);
  st = service.check();
  if (!st.ok()) return report("serve", st);
  serve::Server server;
  st = server.listen(o);
  if (st.is_invalid_argument()) return usage_error("serve", st.message(), kUsage);
  if (!st.ok()) return report("serve", st);
  service.set_callers(serve::caller_policy(o.bind, server.port(), allowed_hosts(args)));
  if (args.values.count("scratch")) service.set_scratch(args.values.at("scratch"));
  g_server = &server;
  std::signal(SIGINT, stop_serving);
  std::signal(SIGTERM, stop_serving);
  std::printf("weaver serve: %s on http://%s:%d/ (%d threads; Ctrl-C stops)\n", db.c_str(),
              o.bind.c_str(), server.port(), o.threads);
  std::fflush(stdout);
  server.serve([&](const serve::Request& r) { return service.handle(r); }, [&] { service.warm(); });
  g_server = nullptr;
  std::printf("weaver serve: stopped\n");
  return 0;
}

}  // namespace weaver::cli
