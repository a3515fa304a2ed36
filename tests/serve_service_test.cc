// serve/service: the real handler (the routes, each thread's Explorer, the
// leaf directories shared among them, the helper a large batch borrows,
// the batch lane and the colour ranges kept for every tile of a section)
// answering from several threads at once exactly what it answers from one.
// Runs under ThreadSanitizer too (the "tsan" preset takes *Thread* tests).
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "cli/serve_queries.h"
#include "construct/construct.h"
#include "extract/extract.h"
#include "serve/service.h"
#include "test_mesh.h"
#include "test_octrees.h"

namespace weaver {
namespace {

// A sink that keeps what a streamed answer writes.
class StringSink : public serve::BodySink {
 public:
  bool write(const char* data, size_t n) override {
    bytes.append(data, n);
    return true;
  }
  std::string bytes;
};

serve::Request request_of(const std::string& method, const std::string& target,
                          std::string body = "") {
  serve::Request r;
  bool too_large = false;
  EXPECT_OK(serve::parse_request_head(method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1:8080",
                                      &r, &too_large));
  r.body = std::move(body);
  return r;
}

// The status and the whole body of the answer to r.
std::string answer(serve::Service& s, const serve::Request& r) {
  serve::Response res = s.handle(r);
  std::string body = res.body;
  if (res.stream) {
    StringSink sink;
    const serve::Response end = res.stream(sink);
    body = end.status == 200 ? sink.bytes : end.body;
    res.status = end.status;
  }
  return std::to_string(res.status) + " " + body;
}

TEST(ServeServiceThreads, ManyThreadsAnswerAsOne) {
  testing::TempDir dir;
  const std::string db = testing::build_mesh(testing::random_balanced(5, 2, 2, 1, 2, 3000, 9), dir);
  // A lane of 4096 points: the batch below answers in several lanes' worth.
  serve::Service service(db, MemoryBudget(16 << 20), 4 << 20, cli::serve_query_runner(), 4096);
  service.set_callers(serve::caller_policy("127.0.0.1", 8080, {}));
  std::string points;  // past 256 KiB: the batch borrows the helper and the lane
  for (int i = 0; points.size() < (300 << 10); ++i) {
    points += std::to_string(i * 7919 % 1048576) + " " + std::to_string(i * 3571 % 1048576) + " " +
              std::to_string(i * 997 % 524288) + "\n";
  }
  std::vector<serve::Request> asked = {
      request_of("GET", "/api/stat"),
      request_of("GET", "/api/element/17"),
      request_of("GET", "/api/neighbors/17?kinds=all"),
      request_of("GET", "/api/locate?x=1000&y=2000&z=3000"),
      request_of("GET", "/api/range?box=0,0,0,600000,600000,300000&list=1&limit=500&from=20"),
      request_of("GET", "/api/section/z/1000?color=level"),
      request_of("GET", "/api/tile/z/1000/0/0/0.png?color=level"),
      request_of("GET", "/api/tile/x/500/2/1/1.png?color=edge"),
      request_of("POST", "/api/points", points),
  };
  std::vector<std::string> want;
  for (const serve::Request& r : asked) want.push_back(answer(service, r));
  for (const std::string& w : want) ASSERT_EQ(w.rfind("200 ", 0), 0u) << w.substr(0, 200);

  constexpr int kThreads = 4, kRounds = 3;
  std::vector<std::vector<std::string>> got(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < kRounds; ++round) {
        for (size_t i = 0; i < asked.size(); ++i) {
          const size_t k = (i + size_t(t) * 3 + size_t(round)) % asked.size();  // orders differ
          got[t].push_back(std::to_string(k) + ":" + answer(service, asked[k]));
        }
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < kThreads; ++t) {
    ASSERT_EQ(got[t].size(), asked.size() * kRounds);
    for (const std::string& g : got[t]) {
      const size_t k = std::stoul(g.substr(0, g.find(':')));
      EXPECT_TRUE(g.substr(g.find(':') + 1) == want[k])
          << "thread " << t << ", request " << k << ": " << g.substr(0, 160);
    }
  }
}

}  // namespace
}  // namespace weaver

namespace weaver {
namespace {

// z_mode on a mesh under a ground: the same point as the domain's depth and
// as an elevation answers the same element; above the ground, status air;
// an unknown mode is refused.
TEST(ServeService, LocateTakesZModesOnAMeshWithAGround) {
  testing::TempDir dir;
  const std::string dem = dir.file("ramp.asc");
  {
    std::ofstream f(dem);
    f << "ncols 3\nnrows 3\nxllcenter 0\nyllcenter 0\ncellsize 4000\n";
    for (int r = 2; r >= 0; --r) f << "0 300 600\n";
  }
  ConstructOptions o;
  o.model = "loh1";
  o.freq = 0.5;
  o.domain_m = {8000, 8000, 4000};
  o.surface = "asc:" + dem;
  ConstructPlan plan;
  ConstructResult cr;
  const std::string db = dir.file("db");
  ASSERT_OK(construct_octree(db, o, &plan, &cr));
  ExtractResult er;
  ASSERT_OK(extract_mesh(db, ExtractOptions{}, &er));
  serve::Service service(db, MemoryBudget(16 << 20), 4 << 20, cli::serve_query_runner(), 4096);
  service.set_callers(serve::caller_policy("127.0.0.1", 8080, {}));
  const double top = plan.ground.top_elevation;
  char domain[160], elevation[160];
  std::snprintf(domain, sizeof domain, "/api/locate?x=1000&y=6000&z=%.17g&units=m", top - 100);
  std::snprintf(elevation, sizeof elevation, "/api/locate?x=1000&y=6000&z=100&z_mode=elevation");
  const std::string a = answer(service, request_of("GET", domain));
  const std::string b = answer(service, request_of("GET", elevation));
  ASSERT_EQ(a.rfind("200 ", 0), 0u) << a;
  EXPECT_NE(a.find("\"status\": \"inside\""), std::string::npos) << a;
  EXPECT_EQ(a.substr(a.find("\"status\"")), b.substr(b.find("\"status\"")));
  const std::string air =
      answer(service, request_of("GET", "/api/locate?x=1000&y=500&z=590&z_mode=elevation"));
  EXPECT_NE(air.find("\"status\": \"air\""), std::string::npos) << air;
  const std::string bad =
      answer(service, request_of("GET", "/api/locate?x=1&y=1&z=1&z_mode=--points"));
  EXPECT_EQ(bad.rfind("400 ", 0), 0u) << bad;
}

}  // namespace
}  // namespace weaver
