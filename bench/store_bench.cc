// Named workloads over the stores (--backends btree,packed,lsm: the B+tree
// with plain leaves, with packed leaves, and the LSM), in the LevelDB
// tradition, all through the Store interface:
//   fillseq      sorted append of n records, then commit (flush + fsync)
//   readseq      cursor scan of every record
//   getrandom    exact lookups of random present keys
//   floorrandom  aggregate hits: the leaf containing a random pixel
//   fillrandom   random-order inserts of n records, then commit; the LSM
//                compacts first, so both end as one B+tree file
// The LSM's memtable gets the small pool as its budget; its reads run on the
// store fillseq left (compacted: one run).
// Records are octant keys (the first n level-8 octants in Z-order, so the
// domain is their union) with a 16-byte payload.  Every workload runs in its
// own child process, so its peak RSS is its own.  Prints one JSON object per
// run, then a table of medians.
#include <sys/mman.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "bench_util.h"
#include "schema/octant.h"
#include "storage/btree.h"
#include "storage/lsm.h"

namespace weaver::bench {
namespace {

constexpr uint32_t kPayload = 16;
constexpr int kGridLevel = 8;  // 16.7M octants: room for 10M records

struct Config {
  std::vector<uint64_t> sizes = {1'000'000, 10'000'000};
  uint64_t small_pool = 20ull << 20;
  uint64_t large_pool = 512ull << 20;
  uint64_t queries = 2'000'000;
  int repeat = 3;
  std::string dir = "/tmp/weaver-bench";
  std::vector<std::string> workloads = {"fillseq", "readseq", "getrandom", "floorrandom",
                                        "fillrandom"};
  std::vector<std::string> backends = {"btree", "lsm"};
};

uint64_t key_of(uint64_t i) {
  const Coord c = morton_decode(i << (3 * (kMaxLevel - kGridLevel)));
  return octant_key({c.x, c.y, c.z, kGridLevel});
}

void payload_of(uint64_t i, std::byte* out) {
  const uint64_t a = i, b = i * 0x9E3779B97F4A7C15ULL;
  std::memcpy(out, &a, 8);
  std::memcpy(out + 8, &b, 8);
}

uint64_t splitmix(uint64_t* s) {
  uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// A pseudo-random permutation of [0, n): a 4-round Feistel network over the
// smallest even number of bits covering n, walking the cycle until the
// result falls below n.  Every index comes out exactly once, in an order
// with no arithmetic pattern (unlike i * step mod n).
class Permutation {
 public:
  explicit Permutation(uint64_t n) : n_(n) {
    while ((uint64_t{1} << (2 * half_bits_)) < n) ++half_bits_;
    mask_ = (uint64_t{1} << half_bits_) - 1;
  }
  uint64_t operator()(uint64_t i) const {
    do i = feistel(i);
    while (i >= n_);
    return i;
  }

 private:
  uint64_t feistel(uint64_t v) const {
    uint64_t l = v >> half_bits_, r = v & mask_;
    for (uint64_t round = 0; round < 4; ++round) {
      uint64_t s = r * 0x9E3779B97F4A7C15ULL + round;
      const uint64_t f = splitmix(&s) & mask_;
      const uint64_t next = l ^ f;
      l = r;
      r = next;
    }
    return (l << half_bits_) | r;
  }
  uint64_t n_;
  int half_bits_ = 1;
  uint64_t mask_ = 1;
};

TableOptions table_options(bool packed = false) {
  TableOptions o;
  std::string err;
  o.schema = *RecordSchema::parse("a:u64,b:u64", &err);
  o.key_kind = KeyKind::kOctant;
  o.packed = packed;
  return o;
}

// A store of any backend; `path` names a file (B+tree) or a directory (LSM).
struct Backend {
  std::string name;
  uint64_t memtable_bytes = 0;  // LSM only
  std::string path(const std::string& dir, const std::string& what) const {
    return dir + "/" + what + (name == "lsm" ? ".lsm" : name == "packed" ? ".pbt" : ".bt");
  }
};

LsmOptions lsm_options(const Backend& b, uint64_t pool) {
  LsmOptions o;
  o.table = table_options();
  o.memtable_bytes = b.memtable_bytes;
  o.run_pool_bytes = pool;
  return o;
}

bool report(const Status& st) {
  if (!st.ok()) std::fprintf(stderr, "%s\n", st.to_string().c_str());
  return st.ok();
}

bool create_store(const Backend& b, const std::string& path, uint64_t pool,
                  std::unique_ptr<Store>* out) {
  if (b.name == "lsm") {
    std::filesystem::remove_all(path);
    std::unique_ptr<LsmTree> t;
    // Runs are only merged while filling, by cursors: a small pool each.
    if (!report(LsmTree::create(path, lsm_options(b, 1 << 20), &t))) return false;
    *out = std::move(t);
    return true;
  }
  std::unique_ptr<File> f;
  std::unique_ptr<BTree> t;
  Status st = open_posix_file(path, OpenMode::kCreateTruncate, &f);
  if (st.ok()) st = BTree::create(std::move(f), table_options(b.name == "packed"), pool, &t);
  *out = std::move(t);
  return report(st);
}

bool open_store(const Backend& b, const std::string& path, uint64_t pool,
                std::unique_ptr<Store>* out) {
  if (b.name == "lsm") {
    std::unique_ptr<LsmTree> t;
    if (!report(LsmTree::open(path, lsm_options(b, pool), &t))) return false;
    *out = std::move(t);
    return true;
  }
  std::unique_ptr<File> f;
  std::unique_ptr<BTree> t;
  Status st = open_posix_file(path, OpenMode::kReadOnly, &f);
  if (st.ok()) st = BTree::open(std::move(f), pool, &t);
  *out = std::move(t);
  return report(st);
}

void describe(Json* j, const Backend& b, const std::string& w, uint64_t n, uint64_t pool,
              double secs, uint64_t ops, const char* rate_name) {
  j->add("bench", "store").add("backend", b.name).add("workload", w).add("n", n);
  j->add(rate_name, ops / secs).add("seconds", secs).add("pool_bytes", pool);
}

// File size per record, and the B+tree's height (of the LSM's one run).
void describe_size(Json* j, Store& s, uint64_t n) {
  auto* lsm = dynamic_cast<LsmTree*>(&s);
  const BTree* t = lsm != nullptr ? lsm->compacted_run() : dynamic_cast<BTree*>(&s);
  const uint64_t bytes = lsm != nullptr ? lsm->file_bytes() : t->file_bytes();
  const double bpr = double(bytes) / double(n);
  j->add("bytes_per_record", bpr).add("overhead_pct", 100.0 * (bpr / (8 + kPayload) - 1));
  if (t != nullptr) j->add("height", uint64_t{t->height()});
}

bool fill(const Backend& b, const std::string& path, uint64_t n, uint64_t pool, bool random,
          Json* j) {
  std::unique_ptr<Store> t;
  if (!create_store(b, path, pool, &t)) return false;
  const Permutation order(n);
  std::byte payload[kPayload];
  const double t0 = now_seconds();
  for (uint64_t i = 0; i < n; ++i) {
    const uint64_t r = random ? order(i) : i;
    payload_of(r, payload);
    const Status st = random ? t->put(key_of(r), payload, nullptr) : t->append(key_of(r), payload);
    if (!report(st)) return false;
  }
  auto* lsm = dynamic_cast<LsmTree*>(t.get());
  uint64_t runs_before = 0;
  if (lsm != nullptr) {
    runs_before = lsm->run_count();
    if (!report(lsm->compact())) return false;
  }
  if (!report(t->commit())) return false;
  const double secs = now_seconds() - t0;
  describe(j, b, random ? "fillrandom" : "fillseq", n, pool, secs, n, "records_per_s");
  describe_size(j, *t, n);
  if (lsm != nullptr) {
    j->add("memtable_bytes", b.memtable_bytes).add("runs_before_compaction", runs_before);
    j->add("write_amplification", double(lsm->records_written()) / double(n));
  }
  return t->size() == n;
}

bool readseq(const Backend& b, const std::string& path, uint64_t n, uint64_t pool, Json* j) {
  std::unique_ptr<Store> t;
  if (!open_store(b, path, pool, &t)) return false;
  const double t0 = now_seconds();
  std::unique_ptr<Cursor> c;
  if (!report(t->seek(0, &c))) return false;
  uint64_t count = 0, sum = 0;
  while (c->valid()) {
    sum += c->key() + page::load64(c->payload());
    ++count;
    if (!report(c->next())) return false;
  }
  const double secs = now_seconds() - t0;
  describe(j, b, "readseq", n, pool, secs, count, "records_per_s");
  describe_size(j, *t, n);
  j->add("checksum", sum & 0xffff);
  return count == n;
}

// A lookup's key and the answer it must give: the payload's first word
// (getrandom) or the floor's key (floorrandom).
struct Query {
  uint64_t key;
  uint64_t expect;
};

// The next `count` queries of a pass.
void make_queries(uint64_t n, bool floor, uint64_t* seed, size_t count, std::vector<Query>* out) {
  out->resize(count);
  for (Query& q : *out) {
    const uint64_t i = splitmix(seed) % n;
    if (floor) {
      // A random pixel inside octant i: its Morton code shares i's prefix.
      const uint64_t span_bits = 3 * (kMaxLevel - kGridLevel);
      const uint64_t m = (i << span_bits) | (splitmix(seed) & ((1ull << span_bits) - 1));
      q = {pixel_key(morton_decode(m)), key_of(i)};
    } else {
      q = {key_of(i), i};
    }
  }
}

// One pass of random lookups, its seconds added to *secs; returns false on
// an error or a wrong answer.  Queries are made in batches outside the
// timed loops: a query's Morton decode and encode cost about as much as a
// lookup in the pool, and the rate is the store's.
bool lookup_pass(Store& t, uint64_t n, uint64_t queries, bool floor, uint64_t seed, double* secs) {
  constexpr size_t kBatch = 1 << 16;
  std::vector<Query> batch;
  uint64_t wrong = 0;
  std::byte payload[kPayload];
  for (uint64_t done = 0; done < queries; done += batch.size()) {
    make_queries(n, floor, &seed, std::min<uint64_t>(kBatch, queries - done), &batch);
    const double t0 = now_seconds();
    for (const Query& q : batch) {
      bool found = false;
      uint64_t k = 0;
      if (floor) {
        if (!report(t.floor(q.key, &k, payload, &found))) return false;
      } else {
        if (!report(t.get(q.key, payload, &found))) return false;
        k = page::load64(payload);
      }
      wrong += !found || k != q.expect;
    }
    *secs += now_seconds() - t0;
  }
  return wrong == 0;
}

// A cold pass (fresh pool: reads and first-touch faults) and then a warm,
// steady-state pass with other random keys; both rates are reported.
bool lookups(const Backend& b, const std::string& path, uint64_t n, uint64_t pool, uint64_t queries,
             bool floor, Json* j) {
  std::unique_ptr<Store> t;
  if (!open_store(b, path, pool, &t)) return false;
  double cold = 0, warm = 0;
  if (!lookup_pass(*t, n, queries, floor, 42, &cold)) return false;
  if (!lookup_pass(*t, n, queries, floor, 4242, &warm)) return false;
  describe(j, b, floor ? "floorrandom" : "getrandom", n, pool, warm, queries, "queries_per_s");
  j->add("cold_queries_per_s", queries / cold);
  describe_size(j, *t, n);
  return true;
}

// The machine's floor for a lookup that misses the CPU caches: one
// dependent random read over a buffer as large as the tree (huge pages
// advised, as the pool's frames are), in reads per second.  A lookup chains
// at least one such miss (its leaf), so no single-stream lookup rate beats it.
bool memory_latency(uint64_t bytes, Json* j) {
  constexpr size_t kHuge = size_t{2} << 20;
  const size_t n = (bytes + kHuge - 1) / kHuge * kHuge / 8;
  std::unique_ptr<uint64_t[], decltype(&std::free)> buf(
      static_cast<uint64_t*>(std::aligned_alloc(kHuge, n * 8)), &std::free);
  if (!buf) return false;
#ifdef MADV_HUGEPAGE
  ::madvise(buf.get(), n * 8, MADV_HUGEPAGE);
#endif
  uint64_t seed = 7;
  for (size_t i = 0; i < n; ++i) buf[i] = splitmix(&seed);
  const uint64_t reads = 2'000'000;
  uint64_t x = 0;
  const double t0 = now_seconds();
  for (uint64_t r = 0; r < reads; ++r) x = buf[(x ^ splitmix(&seed)) % n];
  const double secs = now_seconds() - t0;
  j->add("bench", "store").add("backend", "memory").add("workload", "dependent_read");
  j->add("n", uint64_t{n}).add("queries_per_s", reads / secs);
  j->add("ns_per_read", 1e9 * secs / reads).add("checksum", x & 0xff);
  return true;
}

// The floor with a small pool: one 4 KiB pread of a random page of the tree
// file (in the page cache, as the lookups left it), in reads per second.
// A lookup that misses the pool makes at least one.
bool pread_floor(const std::string& path, Json* j) {
  std::unique_ptr<File> f;
  if (!report(open_posix_file(path, OpenMode::kReadOnly, &f))) return false;
  uint64_t size = 0;
  if (!report(f->size(&size))) return false;
  const uint64_t pages = size / 4096, reads = 200'000;
  std::vector<std::byte> page(4096);
  uint64_t seed = 11, sum = 0;
  const double t0 = now_seconds();
  for (uint64_t r = 0; r < reads; ++r) {
    if (!report(read_fully(*f, (splitmix(&seed) % pages) * 4096, page.data(), 4096))) return false;
    sum += static_cast<uint64_t>(page[100]);
  }
  const double secs = now_seconds() - t0;
  j->add("bench", "store").add("backend", "file").add("workload", "pread_4k");
  j->add("n", pages).add("queries_per_s", reads / secs).add("checksum", sum & 0xff);
  return true;
}

std::string median_of(std::vector<std::map<std::string, std::string>>& runs, const char* key) {
  std::vector<double> v;
  for (auto& r : runs) {
    if (r.count(key)) v.push_back(std::stod(r[key]));
  }
  return v.empty() ? "" : fmt(median(v));
}

// Runs one of the floors `repeat` times and adds its median row.
void add_floor_row(const std::function<bool(Json*)>& floor, int repeat,
                   std::vector<std::map<std::string, std::string>>* table) {
  std::vector<std::map<std::string, std::string>> runs;
  for (int r = 0; r < repeat; ++r) {
    const std::string line = run_in_child(floor);
    if (line.empty()) continue;
    std::printf("%s\n", line.c_str());
    runs.push_back(parse_flat_json(line));
  }
  if (runs.empty()) return;
  auto row = runs[0];
  row["queries_per_s"] = median_of(runs, "queries_per_s");
  row["peak_rss_bytes"] = median_of(runs, "peak_rss_bytes");
  row["runs"] = std::to_string(runs.size());
  table->push_back(row);
}

uint64_t parse_size(const std::string& s) {
  double v = std::stod(s);
  const char u = s.empty() ? 0 : s.back();
  if (u == 'K' || u == 'k') v *= 1e3;
  if (u == 'M' || u == 'm') v *= 1e6;
  if (u == 'G' || u == 'g') v *= 1e9;
  return static_cast<uint64_t>(v);
}

uint64_t parse_bytes(const std::string& s) {
  double v = std::stod(s);
  const char u = s.empty() ? 0 : s.back();
  if (u == 'K' || u == 'k') v *= 1024;
  if (u == 'M' || u == 'm') v *= 1024 * 1024;
  if (u == 'G' || u == 'g') v *= 1024.0 * 1024 * 1024;
  return static_cast<uint64_t>(v);
}

std::vector<std::string> split_commas(const std::string& s) {
  std::vector<std::string> out;
  size_t i = 0;
  while (i <= s.size()) {
    const size_t c = s.find(',', i);
    out.push_back(s.substr(i, c == std::string::npos ? std::string::npos : c - i));
    if (c == std::string::npos) break;
    i = c + 1;
  }
  return out;
}

int usage() {
  std::printf(
      "usage: store_bench [--sizes 1M,10M] [--workloads fillseq,readseq,getrandom,floorrandom,"
      "fillrandom]\n"
      "                   [--pool 20M] [--large-pool 512M] [--queries 2M] [--repeat 3]\n"
      "                   [--backends btree,lsm] [--dir /tmp/weaver-bench]\n"
      "Backends: btree (plain leaves), packed (the B+tree with packed leaves, as weaver's\n"
      "mesh tables are), lsm.\n"
      "Lookups run twice: with the small pool and with the large one (which holds the tree).\n"
      "With lookups, two rows give the machine's floors: 'memory dependent_read', dependent\n"
      "random reads per second over a buffer the size of the tree file (a lookup in the\n"
      "pool chains at least one), and 'file pread_4k', random 4 KiB preads of the cached\n"
      "tree file (a lookup that misses the pool makes at least one).\n");
  return 2;
}

}  // namespace
}  // namespace weaver::bench

int main(int argc, char** argv) {
  using namespace weaver::bench;
  Config c;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h" || i + 1 >= argc) return usage();
    const std::string v = argv[++i];
    if (a == "--sizes") {
      c.sizes.clear();
      for (const auto& s : split_commas(v)) c.sizes.push_back(parse_size(s));
    } else if (a == "--backends") {
      c.backends = split_commas(v);
    } else if (a == "--workloads") {
      c.workloads = split_commas(v);
    } else if (a == "--pool") {
      c.small_pool = parse_bytes(v);
    } else if (a == "--large-pool") {
      c.large_pool = parse_bytes(v);
    } else if (a == "--queries") {
      c.queries = parse_size(v);
    } else if (a == "--repeat") {
      c.repeat = std::stoi(v);
    } else if (a == "--dir") {
      c.dir = v;
    } else {
      return usage();
    }
  }
  std::filesystem::create_directories(c.dir);
  std::vector<std::map<std::string, std::string>> table;
  bool all_ok = true;
  for (uint64_t n : c.sizes) {
    for (const std::string& backend : c.backends) {
      const Backend b{backend, c.small_pool};
      const std::string seq_path = b.path(c.dir, "seq"), rnd_path = b.path(c.dir, "rnd");
      for (const std::string& w : c.workloads) {
        std::vector<uint64_t> pools = {c.small_pool};
        if (w == "getrandom" || w == "floorrandom" || w == "readseq") pools.push_back(c.large_pool);
        if (w == "fillrandom") pools = {c.large_pool};
        for (uint64_t pool : pools) {
          std::vector<std::map<std::string, std::string>> runs;
          for (int r = 0; r < c.repeat; ++r) {
            const std::string line = run_in_child([&](Json* j) {
              if (w == "fillseq") return fill(b, seq_path, n, pool, false, j);
              if (w == "fillrandom") return fill(b, rnd_path, n, pool, true, j);
              if (w == "readseq") return readseq(b, seq_path, n, pool, j);
              if (w == "getrandom") return lookups(b, seq_path, n, pool, c.queries, false, j);
              if (w == "floorrandom") return lookups(b, seq_path, n, pool, c.queries, true, j);
              return false;
            });
            if (line.empty()) {
              all_ok = false;
              continue;
            }
            std::printf("%s\n", line.c_str());
            runs.push_back(parse_flat_json(line));
          }
          if (runs.empty()) continue;
          auto row = runs[0];
          for (const char* k : {"records_per_s", "queries_per_s", "cold_queries_per_s", "seconds",
                                "peak_rss_bytes"}) {
            row[k] = median_of(runs, k);
          }
          row["runs"] = std::to_string(runs.size());
          table.push_back(row);
        }
      }
      if (backend == "btree" && std::filesystem::exists(seq_path) &&
          (std::count(c.workloads.begin(), c.workloads.end(), "getrandom") > 0 ||
           std::count(c.workloads.begin(), c.workloads.end(), "floorrandom") > 0)) {
        const uint64_t bytes = std::filesystem::file_size(seq_path);
        add_floor_row([&](Json* j) { return memory_latency(bytes, j); }, c.repeat, &table);
        add_floor_row([&](Json* j) { return pread_floor(seq_path, j); }, c.repeat, &table);
      }
      if (!std::getenv("WEAVER_BENCH_KEEP")) std::filesystem::remove_all(seq_path);
      std::filesystem::remove_all(rnd_path);
    }
  }
  std::printf("\nmedians (octant key + %u-byte payload):\n", kPayload);
  print_table(table, {"backend", "workload", "n", "pool_bytes", "records_per_s", "queries_per_s",
                      "cold_queries_per_s", "bytes_per_record", "overhead_pct", "height",
                      "write_amplification", "peak_rss_bytes", "runs"});
  return all_ok ? 0 : 1;
}
