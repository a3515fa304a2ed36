// `weaver serve` under load, from clients on this machine (127.0.0.1):
//   - point queries over keep-alive connections (GET /api/locate, random
//     points in the domain), requests per second, for a few seconds;
//   - POST /api/points of 1M random points with material, points per second;
//   - tiles over HTTP (GET /api/tile at zooms 0 to 9), milliseconds each,
//     median and 95th percentile.
// The server is `weaver serve DB --port 0` in a process of its own; the
// clients share the machine's cores with it.  Default: the basin's 0.5 Hz
// mesh (built here); --db DB for any mesh.  One JSON object per
// measurement, then a table.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "basin_stages.h"
#include "bench_util.h"

namespace weaver::bench {
namespace {

int connect_to(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// Sends one request on fd and reads its whole response; the status, or -1.
// The body of a chunked answer, whole once got holds its last chunk: true
// and *body (when asked) when it does.
bool dechunk(const std::string& got, size_t from, std::string* body) {
  std::string out;
  for (size_t at = from;;) {
    const size_t eol = got.find("\r\n", at);
    if (eol == std::string::npos) return false;
    const size_t n = std::stoull(got.substr(at, eol - at), nullptr, 16);
    if (n == 0) {
      if (got.size() < eol + 4) return false;
      if (body != nullptr) *body = std::move(out);
      return true;
    }
    if (got.size() < eol + 2 + n + 2) return false;
    if (body != nullptr) out.append(got, eol + 2, n);
    at = eol + 2 + n + 2;
  }
}

// Sends request and reads its answer (Content-Length or chunked): the
// status, and the body when asked.  expect: the bytes the answer will
// about take, reserved at once (the client shares the cores it measures).
int exchange(int fd, const std::string& request, std::string* body, size_t expect = 0) {
  if (::send(fd, request.data(), request.size(), MSG_NOSIGNAL) != ssize_t(request.size())) {
    return -1;
  }
  std::string got;
  got.reserve(expect);
  char buf[1 << 16];
  size_t head_end = std::string::npos, length = 0;
  bool chunked = false;
  for (;;) {
    if (head_end == std::string::npos) {
      head_end = got.find("\r\n\r\n");
      if (head_end != std::string::npos) {
        const size_t at = got.find("Content-Length: ");
        length = at < head_end ? std::stoull(got.substr(at + 16)) : 0;
        chunked = got.find("Transfer-Encoding: chunked") < head_end;
      }
    }
    if (head_end != std::string::npos && chunked) {
      // Only the last few bytes tell whether the last chunk is in.
      if (got.size() >= 5 && got.compare(got.size() - 5, 5, "0\r\n\r\n") == 0 &&
          dechunk(got, head_end + 4, body)) {
        break;
      }
    } else if (head_end != std::string::npos && got.size() >= head_end + 4 + length) {
      if (body != nullptr) *body = got.substr(head_end + 4, length);
      break;
    }
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) return -1;
    got.append(buf, size_t(n));
  }
  return std::stoi(got.substr(9, 3));
}

// "Host: 127.0.0.1:PORT\r\n": the server answers only its own names (421).
std::string g_host;

std::string get(const std::string& path) {
  return "GET " + path + " HTTP/1.1\r\n" + g_host + "\r\n";
}

}  // namespace

int serve_main(int argc, char** argv) {
  std::string db;
  double freq = 0.5, seconds = 5;
  int clients = 2;
  uint64_t batch = 1000000;
  int given_port = 0;
  std::string memory = "1G";  // a server already running there (for perf)
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--db" && i + 1 < argc) {
      db = argv[++i];
    } else if (a == "--freq" && i + 1 < argc) {
      freq = std::stod(argv[++i]);
    } else if (a == "--seconds" && i + 1 < argc) {
      seconds = std::stod(argv[++i]);
    } else if (a == "--memory" && i + 1 < argc) {
      memory = argv[++i];
    } else if (a == "--clients" && i + 1 < argc) {
      clients = std::stoi(argv[++i]);
    } else if (a == "--points" && i + 1 < argc) {
      batch = std::stoull(argv[++i]);
    } else if (a == "--port" && i + 1 < argc) {
      given_port = std::stoi(argv[++i]);
    } else {
      std::printf(
          "usage: serve_bench [--db DB | --freq F] [--seconds S] [--clients N] [--points N]\n"
          "                   [--memory BYTES (the server's; default 1G)]\n"
          "                   [--port P (a server already running there)]\n");
      return 2;
    }
  }
  if (db.empty() && (db = basin_mesh(freq)).empty()) {
    return std::fprintf(stderr, "cannot build the %g Hz basin mesh\n", freq), 1;
  }

  // The server, and the port it says.
  pid_t server = -1;
  int port = given_port;
  if (port == 0) {
    int out[2];
    if (::pipe(out) != 0) return 1;
    server = ::fork();
    if (server == 0) {
      ::dup2(out[1], 1);
      ::close(out[0]);
      ::execl(WEAVER_BINARY, WEAVER_BINARY, "serve", db.c_str(), "--port", "0", "--memory",
              memory.c_str(), "--quiet", static_cast<char*>(nullptr));
      std::_Exit(127);
    }
    ::close(out[1]);
    std::string line;
    char c;
    while (::read(out[0], &c, 1) == 1 && c != '\n') line += c;
    const size_t at = line.find("127.0.0.1:");
    if (at == std::string::npos) return std::fprintf(stderr, "no URL: %s\n", line.c_str()), 1;
    port = std::stoi(line.substr(at + 10));
  }
  g_host = "Host: 127.0.0.1:" + std::to_string(port) + "\r\n";

  std::string stat;
  {
    const int fd = connect_to(port);
    exchange(fd, get("/api/stat"), &stat);
    ::close(fd);
  }
  // "extent_m": [x, y, z]
  double extent[3] = {0, 0, 0};
  std::sscanf(stat.c_str() + stat.find("\"extent_m\": [") + 13, "%lf, %lf, %lf", &extent[0],
              &extent[1], &extent[2]);
  const uint64_t elements = std::stoull(stat.substr(stat.find("\"elements\": ") + 12));
  std::vector<std::map<std::string, std::string>> table;
  auto emit = [&](const std::string& what, const std::string& unit, double value,
                  const std::string& extra) {
    Json j;
    j.add("bench", "serve").add("db", db).add("elements", elements).add("what", what);
    j.add(unit, value);
    std::printf("%s\n", j.str().c_str());
    table.push_back({{"what", what}, {"value", fmt(value) + " " + unit}, {"note", extra}});
  };

  // Point queries on keep-alive connections.
  std::atomic<uint64_t> answered{0}, failed{0};
  const double t_end = now_seconds() + seconds;
  std::vector<std::thread> threads;
  for (int k = 0; k < clients; ++k) {
    threads.emplace_back([&, k] {
      std::mt19937_64 rng(k + 1);
      int fd = connect_to(port);
      char path[160];
      while (now_seconds() < t_end) {
        std::snprintf(path, sizeof path, "/api/locate?x=%.1f&y=%.1f&z=%.1f&units=m",
                      extent[0] * double(rng() % 100000) / 1e5,
                      extent[1] * double(rng() % 100000) / 1e5,
                      extent[2] * double(rng() % 100000) / 1e5);
        if (fd < 0 || exchange(fd, get(path), nullptr) != 200) {
          ++failed;
          if (fd >= 0) ::close(fd);
          fd = connect_to(port);  // the server closed it (its request limit)
          continue;
        }
        ++answered;
      }
      if (fd >= 0) ::close(fd);
    });
  }
  for (auto& t : threads) t.join();
  emit("GET /api/locate, keep-alive", "requests_per_s", answered / seconds,
       std::to_string(clients) + " clients, " + std::to_string(failed.load()) + " reconnects");

  // One POST of many points.
  {
    std::mt19937_64 rng(9);
    std::string body;
    body.reserve(batch * 24);
    char p[96];
    for (uint64_t i = 0; i < batch; ++i) {
      const int n = std::snprintf(
          p, sizeof p, "%.1f %.1f %.1f\n", extent[0] * double(rng() % 100000) / 1e5,
          extent[1] * double(rng() % 100000) / 1e5, extent[2] * double(rng() % 100000) / 1e5);
      body.append(p, size_t(n));
    }
    const std::string request = "POST /api/points?query=material&units=m HTTP/1.1\r\n" + g_host +
                                "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" +
                                body;
    std::vector<double> rates;
    for (int r = 0; r < 3; ++r) {
      const int fd = connect_to(port);
      std::string answer;
      const double t0 = now_seconds();
      const int status = exchange(fd, request, &answer, batch * 160);
      rates.push_back(batch / (now_seconds() - t0));
      ::close(fd);
      if (status != 200) return std::fprintf(stderr, "POST /api/points: %d\n", status), 1;
      // Every point answered: one row a line.
      const size_t rows = size_t(std::count(answer.begin(), answer.end(), '\n'));
      if (rows != batch) {
        return std::fprintf(stderr, "POST /api/points: %zu rows for %llu points\n", rows,
                            (unsigned long long)batch),
               1;
      }
    }
    emit("POST /api/points with material", "points_per_s", median(rates),
         std::to_string(batch) + " points, median of 3");
  }

  // Tiles over HTTP at zooms 0..9 (the first cold, the rest warm): with the
  // page's colour range, and without one (the server finds the section's
  // range, once for each committed state), alternating.
  for (const int zoom : {0, 3, 6, 9}) {
    std::vector<double> ms[2];
    std::mt19937_64 rng(zoom + 11);
    for (int r = 0; r < 40; ++r) {
      const uint64_t n = uint64_t{1} << zoom;
      const uint64_t x = rng() % n, y = n - 1 - rng() % std::max<uint64_t>(1, n * 3 / 8);
      const bool ranged = r % 2 == 0;
      const std::string path = "/api/tile/z/1000/" + std::to_string(zoom) + "/" +
                               std::to_string(x) + "/" + std::to_string(y) + ".png?color=vs" +
                               (ranged ? "&min=100&max=3900" : "");
      const int fd = connect_to(port);
      const double t0 = now_seconds();
      const int status = exchange(fd, get(path), nullptr);
      ms[ranged ? 0 : 1].push_back((now_seconds() - t0) * 1e3);
      ::close(fd);
      if (status != 200) return std::fprintf(stderr, "%s: %d\n", path.c_str(), status), 1;
    }
    for (int k = 0; k < 2; ++k) {
      std::sort(ms[k].begin(), ms[k].end());
      emit("tile, zoom " + std::to_string(zoom) + (k ? ", no min/max" : ", min/max given"),
           "median_ms", median(ms[k]),
           "95th percentile " + fmt(ms[k][ms[k].size() * 95 / 100]) + " ms, 20 tiles");
    }
  }
  if (server > 0) {
    ::kill(server, SIGTERM);
    int status = 0;
    ::waitpid(server, &status, 0);
  }
  std::printf("\n%s: %llu elements\n", db.c_str(), (unsigned long long)elements);
  print_table(table, {"what", "value", "note"});
  return 0;
}

}  // namespace weaver::bench

int main(int argc, char** argv) { return weaver::bench::serve_main(argc, argv); }
