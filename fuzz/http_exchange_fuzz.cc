// A whole exchange with `weaver serve`: request bytes in (head and body, as
// a client sends them), the service's answer out, against a small mesh
// made once.  Whatever the bytes, the answer has a known status, an error
// is one valid JSON object, a streamed answer ends, and no value reaches an
// option or a file (a request naming one is refused like any other bad
// value).  libFuzzer's -timeout and -rss_limit_mb bound each exchange's
// time and memory (fuzz/run.sh sets them).
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <string>

#include "cli/cli.h"
#include "cli/serve_queries.h"
#include "serve/service.h"

using namespace weaver;

namespace {

serve::Service* g_service = nullptr;

// A sink that takes at most a few MiB, then says the client left.
class CountingSink : public serve::BodySink {
 public:
  bool write(const char*, size_t n) override {
    bytes += n;
    return bytes < (8 << 20);
  }
  size_t bytes = 0;
};

bool known_status(int s) {
  for (int k : {200, 400, 403, 404, 405, 413, 421, 500, 503}) {
    if (s == k) return true;
  }
  return false;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  char dir[] = "/tmp/weaver-fuzz-exchange-XXXXXX";
  if (::mkdtemp(dir) == nullptr) std::abort();
  static std::string db = std::string(dir) + "/basin.db";
  const char* argv[] = {"weaver", "mesh",   db.c_str(), "--model",
                        "basin",  "--freq", "0.05",     "--quiet"};
  if (cli::cmd_mesh(8, const_cast<char**>(argv)) != 0) std::abort();
  static serve::Service service(db, MemoryBudget(16 << 20), 2 << 20, cli::serve_query_runner());
  service.set_callers(serve::caller_policy("127.0.0.1", 8080, {}));
  g_service = &service;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  const size_t end = bytes.find("\r\n\r\n");
  if (end == std::string::npos) return 0;
  serve::Request r;
  bool too_large = false;
  if (!serve::parse_request_head(bytes.substr(0, end), &r, &too_large).ok()) return 0;
  uint64_t length = 0;
  serve::Response refusal;
  if (!serve::body_length(r, 1 << 20, &length, &refusal)) return 0;
  r.body = bytes.substr(end + 4, length);
  serve::Response res = g_service->handle(r);
  if (!known_status(res.status)) std::abort();
  if (res.stream) {
    CountingSink sink;
    const serve::Response ended = res.stream(sink);
    if (!known_status(ended.status)) std::abort();
    res = ended;
  }
  if (res.status != 200) {
    const std::string& b = res.body;
    if (b.rfind("{\"error\": \"", 0) != 0 || b.size() < 14 || b.compare(b.size() - 3, 3, "\"}\n")) {
      std::abort();
    }
  }
  return 0;
}
