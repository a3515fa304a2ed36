#include <csignal>
#include <cstdio>
#include <cstring>

#include "cli/cli.h"
#include "cli/query_commands.h"
#include "serve/service.h"

namespace weaver::cli {
namespace {

constexpr char kUsage[] =
    "usage: weaver serve DB [--port P] [--bind ADDR] [--threads N] [--memory BYTES]\n"
    "\n"
    "Serves DB read-only over HTTP: a page to explore the mesh in a browser (a\n"
    "cross-section as a zoomable map of tiles, coloured by a field, the element\n"
    "under a click and its neighbours) and a JSON API with the answers of\n"
    "'weaver query --format json'.  Each request reads one committed state; a\n"
    "writer committing meanwhile is seen from the next request on.  With an\n"
    "aggregate table ('weaver aggregate DB') a map pixel that holds many\n"
    "elements shows their least vs (or another summary) rather than the one at\n"
    "its centre.  Limits: 64 connections (more get 503), a request's head 40 KiB\n"
    "and body 64 MiB, 256 MiB of bodies at once, 10 s to send a request (408),\n"
    "5 s idle between two.\n"
    "  --port P        the TCP port (default 8080; 0 for any free one)\n"
    "  --bind ADDR     the IPv4 address to listen on (default 127.0.0.1: this\n"
    "                  machine only; 0.0.0.0 for every interface)\n"
    "  --threads N     requests answered at once (default 4); a slow or idle\n"
    "                  client holds a connection, never a thread\n"
    "  --memory BYTES  memory budget, shared by the threads (default 256M)\n"
    "Routes:\n"
    "  /                                  the page\n"
    "  /api/stat                          counts, units, extents, fields\n"
    "  /api/locate?x=&y=&z=[&units=m|ticks][&geo=1]\n"
    "  POST /api/points[?query=locate|material|node-at][&units=m]  lines or [[x,y,z],...]\n"
    "  /api/element/ID  /api/node/ID  /api/neighbors/ID[?kinds=all]\n"
    "  /api/node-elements/ID  /api/depends/ID\n"
    "  /api/range?box=X0,Y0,Z0,X1,Y1,Z1[&list=1]\n"
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

// A stdio stream that appends to a std::string: a query's answer lands in
// the response without a copy (a million points are about 130 MB of JSON).
std::FILE* string_stream(std::string* s) {
  cookie_io_functions_t io{};
  io.write = [](void* cookie, const char* data, size_t n) -> ssize_t {
    static_cast<std::string*>(cookie)->append(data, n);
    return ssize_t(n);
  };
  return fopencookie(s, "w", io);
}

// A query of `weaver query` on an open Explorer, its output captured.
int run_captured(Explorer& ex, const std::vector<std::string>& words, const std::string& points,
                 std::string* out, std::string* err) {
  out->clear(), err->clear();
  std::FILE* o = string_stream(out);
  std::FILE* e = string_stream(err);
  std::FILE* in = fmemopen(const_cast<char*>(points.empty() ? "" : points.data()),
                           points.empty() ? 1 : points.size(), "r");
  QuerySettings settings;
  settings.points_stdin = in;
  const int code = o && e && in ? run_query(ex, words, settings, o, e, "weaver serve") : 1;
  if (in) std::fclose(in);
  if (o) std::fclose(o);  // flushes into *out
  if (e) std::fclose(e);
  return code;
}

}  // namespace

int cmd_serve(int argc, char** argv) {
  ParsedArgs args;
  Status st = parse_args(argc, argv, 2, {"port", "bind", "threads", "memory"}, {}, &args);
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
  // Each thread keeps an Explorer of its own: each gets its share.
  const MemoryBudget each(std::max<uint64_t>(memory.bytes() / o.threads, MemoryBudget::kMinBytes));
  serve::Service service(db, each, run_captured);
  st = service.check();
  if (!st.ok()) return report("serve", st);
  serve::Server server;
  st = server.listen(o);
  if (st.is_invalid_argument()) return usage_error("serve", st.message(), kUsage);
  if (!st.ok()) return report("serve", st);
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
