// The packed leaf codec (storage/packed_leaf.h): every key and payload comes
// back from every access path on octree leaves, mesh node keys and arbitrary
// keys; the models compress what they are for; and damaged pages read as
// damaged, never out of bounds (the sanitizer build checks the latter).
#include "storage/packed_leaf.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <random>
#include <vector>

#include "schema/octant.h"
#include "storage/packed_bits.h"
#include "storage/page_format.h"
#include "test_util.h"

namespace weaver::page {
namespace {

struct Entries {
  std::vector<uint64_t> keys;
  std::vector<std::byte> vals;
};

RecordSchema schema_of(const char* text) {
  std::string error;
  return *RecordSchema::parse(text, &error);
}

struct Refinement {
  int min_level, max_level;
  double refine;  // chance that an octant between the two levels is split
  double hole;    // chance that a subtree is left out (a domain that is not a cube)
};

// Leaves of a random octree below `o`, in key order.
void octree_leaves(const Octant& o, std::mt19937_64& rng, const Refinement& r,
                   std::vector<uint64_t>* out) {
  std::uniform_real_distribution<> coin(0, 1);
  if (o.level > r.min_level && coin(rng) < r.hole) return;
  if (o.level >= r.max_level || (o.level >= r.min_level && coin(rng) >= r.refine)) {
    out->push_back(octant_key(o));
    return;
  }
  for (int k = 0; k < 8; ++k) octree_leaves(octant_child(o, k), rng, r, out);
}

// Node keys of a graded mesh: all grid points of spacing 2^s in boxes of
// different spacing, deduplicated and sorted.
std::vector<uint64_t> graded_node_keys(std::mt19937_64& rng) {
  std::vector<uint64_t> keys;
  for (int box = 0; box < 6; ++box) {
    const uint32_t s = 1u << (4 + rng() % 6), n = 6 + rng() % 10;
    const uint32_t x0 = s * (rng() % 40), y0 = s * (rng() % 40), z0 = s * (rng() % 40);
    for (uint32_t i = 0; i <= n; ++i)
      for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t k = 0; k <= n; ++k)
          keys.push_back(node_key({x0 + i * s, y0 + j * s, z0 + k * s}));
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

std::vector<uint64_t> random_keys(std::mt19937_64& rng, size_t n) {
  std::vector<uint64_t> keys = {0, UINT64_MAX, 1, UINT64_MAX - 1};
  for (size_t i = 0; i < n; ++i) keys.push_back(rng() >> (rng() % 64));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

// Payloads: constant runs, small ranges and full-width noise by turns.
std::vector<std::byte> payloads(std::mt19937_64& rng, size_t n, uint32_t size) {
  std::vector<std::byte> v(n * size);
  const int style = static_cast<int>(rng() % 3);
  for (size_t i = 0; i < v.size(); ++i) {
    const uint64_t r = rng();
    v[i] = std::byte(style == 0 ? (i / size / 500) & 0xff : style == 1 ? r % 3 : r & 0xff);
  }
  return v;
}

// Packs entries into as many pages as they need; checks each page against
// them through every reader; returns the page count.
size_t pack_and_check(const PackedShape& shape, const Entries& e, std::mt19937_64& rng) {
  std::vector<std::byte> page(shape.page_size);
  PackedLeafBuilder b(shape);
  size_t pages = 0;
  for (size_t from = 0; from < e.keys.size();) {
    b.clear();
    const size_t to = b.add_range(e.keys.data(), e.vals.data(), static_cast<uint32_t>(from),
                                  static_cast<uint32_t>(e.keys.size()));
    EXPECT_GT(to, from) << "one entry always fits";
    EXPECT_LE(b.encoded_bytes(), shape.page_size);
    std::fill(page.begin(), page.end(), std::byte{0xa5});  // stale bytes must not matter
    b.encode(page.data());
    ++pages;
    // add_range checks sizes a group at a time: the same page as one by one.
    PackedLeafBuilder single(shape);
    size_t end = from;
    while (end < e.keys.size() && single.add(e.keys[end], e.vals.data() + end * shape.payload)) {
      ++end;
    }
    EXPECT_EQ(end, to);
    std::vector<std::byte> single_page(shape.page_size, std::byte{0xa5});
    single.encode(single_page.data());
    EXPECT_TRUE(single_page == page);
    PackedLeaf leaf;
    EXPECT_TRUE(leaf.open(page.data(), shape));
    const auto n = static_cast<uint32_t>(to - from);
    EXPECT_EQ(leaf.size(), n);
    std::vector<uint64_t> keys(n);
    std::vector<std::byte> vals(size_t{n} * shape.payload), one(shape.payload);
    EXPECT_TRUE(leaf.decode(keys.data(), vals.data()));
    EXPECT_TRUE(std::equal(keys.begin(), keys.end(), e.keys.begin() + from));
    EXPECT_TRUE(std::equal(vals.begin(), vals.end(), e.vals.begin() + from * shape.payload));
    for (int q = 0; q < 200; ++q) {
      const uint32_t i = static_cast<uint32_t>(rng() % n);
      uint64_t k = 0;
      EXPECT_TRUE(leaf.key(i, &k));
      EXPECT_EQ(k, keys[i]);
      leaf.payload(i, one.data());
      EXPECT_TRUE(std::equal(one.begin(), one.end(), vals.begin() + size_t{i} * shape.payload));
      for (const uint64_t probe :
           {keys[i], keys[i] - 1, keys[i] + 1, uint64_t(rng()), uint64_t{0}}) {
        for (const bool upper : {false, true}) {
          uint32_t pos = 0;
          uint64_t below = 0, at = 0;
          EXPECT_TRUE(leaf.bound(probe, upper, &pos, &below, &at));
          const auto want = upper ? std::upper_bound(keys.begin(), keys.end(), probe)
                                  : std::lower_bound(keys.begin(), keys.end(), probe);
          EXPECT_EQ(pos, want - keys.begin()) << "probe " << probe << (upper ? " upper" : " lower");
          // The keys either side of the answer, from the same block search.
          if (pos > 0) {
            EXPECT_EQ(below, keys[pos - 1]) << "probe " << probe;
          }
          if (pos < n) {
            EXPECT_EQ(at, keys[pos]) << "probe " << probe;
          }
        }
      }
    }
    from = to;
  }
  return pages;
}

struct Case {
  const char* name;
  KeyKind kind;
  std::function<std::vector<uint64_t>(std::mt19937_64&)> keys;
};

TEST(PackedLeaf, EveryReaderReturnsWhatWasPacked) {
  const Case cases[] = {
      {"octree", KeyKind::kOctant,
       [](std::mt19937_64& rng) {
         std::vector<uint64_t> k;
         octree_leaves({0, 0, 0, 0}, rng, {3, 9, 0.3, 0}, &k);
         return k;
       }},
      {"octree with holes, to level 20", KeyKind::kOctant,
       [](std::mt19937_64& rng) {
         std::vector<uint64_t> k;
         octree_leaves({1u << 19, 0, 1u << 18, 2}, rng, {4, 20, 0.14, 0.08}, &k);
         return k;
       }},
      {"graded node keys", KeyKind::kNode, graded_node_keys},
      {"arbitrary keys as octant keys", KeyKind::kOctant,
       [](std::mt19937_64& rng) { return random_keys(rng, 3000); }},
      {"arbitrary keys as node keys", KeyKind::kNode,
       [](std::mt19937_64& rng) { return random_keys(rng, 3000); }},
  };
  const char* schemas[] = {"", "kind:u8", "vp:f32,vs:f32,rho:f32", "a:u16,b:i64,c:u8"};
  std::mt19937_64 rng(42);
  for (const Case& c : cases) {
    for (const uint32_t page_size : {256u, 4096u, 65536u}) {
      for (const char* text : schemas) {
        SCOPED_TRACE(std::string(c.name) + ", page " + std::to_string(page_size) + ", schema '" +
                     text + "'");
        const PackedShape shape = PackedShape::of(page_size, c.kind, schema_of(text));
        Entries e;
        e.keys = c.keys(rng);
        ASSERT_GT(e.keys.size(), 100u);
        e.vals = payloads(rng, e.keys.size(), shape.payload);
        pack_and_check(shape, e, rng);
        if (HasFailure()) return;
      }
    }
  }
}

// What the models are for: an octree's leaf keys cost their 5-bit level slot
// and little more; a dense block of node keys costs next to nothing.
TEST(PackedLeaf, ModelsCompressOctreesAndNodeGrids) {
  std::mt19937_64 rng(7);
  Entries octree;
  octree_leaves({0, 0, 0, 0}, rng, {3, 10, 0.3, 0}, &octree.keys);
  ASSERT_GT(octree.keys.size(), 20000u);
  const PackedShape oshape = PackedShape::of(4096, KeyKind::kOctant, schema_of(""));
  const double octant_bytes = 4096.0 * pack_and_check(oshape, octree, rng) / octree.keys.size();
  EXPECT_LT(octant_bytes, 1.0);  // 5 bits of slot + block directory; 8 bytes plain

  Entries grid;
  for (uint32_t i = 0; i < 32; ++i)
    for (uint32_t j = 0; j < 32; ++j)
      for (uint32_t k = 0; k < 32; ++k) grid.keys.push_back(node_key({i * 64, j * 64, k * 64}));
  std::sort(grid.keys.begin(), grid.keys.end());
  grid.vals.assign(grid.keys.size(), std::byte{0});
  const PackedShape nshape = PackedShape::of(4096, KeyKind::kNode, schema_of("kind:u8"));
  const double node_bytes = 4096.0 * pack_and_check(nshape, grid, rng) / grid.keys.size();
  EXPECT_LT(node_bytes, 0.3);  // deltas of one step after the shift: zero-bit residuals
}

// Payloads drawn from a pool of `distinct` random rows, in runs: a mesh's
// materials in Z-order, where neighbours share a depth and so a value.
std::vector<std::byte> pooled_payloads(std::mt19937_64& rng, size_t n, uint32_t size,
                                       size_t distinct) {
  std::vector<std::byte> pool(distinct * size), v(n * size);
  for (std::byte& b : pool) b = std::byte(rng() & 0xff);
  size_t row = 0;
  for (size_t i = 0; i < n; ++i) {
    if (rng() % 4 == 0) row = rng() % distinct;
    std::copy_n(pool.begin() + row * size, size, v.begin() + i * size);
  }
  return v;
}

// Pages whose payloads repeat a few rows store them as a row dictionary
// (coding 1) and hold several times the entries the columns would; every
// reader returns what was packed; rows of noise stay column-wise (coding 0).
TEST(PackedLeaf, RepeatedPayloadsTakeARowDictionary) {
  std::mt19937_64 rng(11);
  Entries e;
  octree_leaves({0, 0, 0, 0}, rng, {3, 10, 0.3, 0}, &e.keys);
  for (const char* text : {"vp:f32,vs:f32,rho:f32", "vp:f32,vs:f32,rho:f32,qp:f32,qs:f32"}) {
    const PackedShape shape = PackedShape::of(4096, KeyKind::kOctant, schema_of(text));
    e.vals = pooled_payloads(rng, e.keys.size(), shape.payload, 12);
    const size_t dictionary_pages = pack_and_check(shape, e, rng);
    std::vector<std::byte> page(shape.page_size);
    PackedLeafBuilder b(shape);
    b.add_range(e.keys.data(), e.vals.data(), 0, static_cast<uint32_t>(e.keys.size()));
    b.encode(page.data());
    EXPECT_EQ(static_cast<int>(page[19]), 1) << text << ": a dictionary page";
    // The same keys with noise for payloads: columns, and many more pages.
    Entries noise = e;
    noise.vals = payloads(rng, e.keys.size(), shape.payload);
    for (std::byte& v : noise.vals) v = std::byte(rng() & 0xff);
    const size_t column_pages = pack_and_check(shape, noise, rng);
    b.clear();
    b.add_range(noise.keys.data(), noise.vals.data(), 0, static_cast<uint32_t>(e.keys.size()));
    b.encode(page.data());
    EXPECT_EQ(static_cast<int>(page[19]), 0) << text << ": a column page";
    EXPECT_GT(column_pages, 5 * dictionary_pages) << text;
  }
}

// Hand-built payloads where the row dictionary has edges: one distinct row
// (columns of width 0 then cost nothing, so no dictionary), alternating rows, exactly as many
// distinct rows as a dictionary may hold and one more, a repetitive run then noise (the dictionary
// given up part way: its rollback), and floats whose bytes differ where their values compare equal
// or not at all (+0.0 and -0.0, NaNs of different payloads, denormals, infinities), for payload
// widths from 4 to 24 bytes.  Every reader must give back the very bytes packed.
TEST(PackedLeaf, DictionaryEdgesRoundTripByteForByte) {
  std::mt19937_64 rng(19);
  Entries e;
  octree_leaves({0, 0, 0, 0}, rng, {3, 9, 0.3, 0}, &e.keys);
  ASSERT_GT(e.keys.size(), 3000u);
  const size_t n = e.keys.size();
  const uint32_t specials[] = {0x00000000, 0x80000000, 0x7fc00000, 0x7fc00001, 0xffc00002,
                               0x7f800001, 0x00000001, 0x807fffff, 0x7f800000, 0xff800000};
  for (const char* text : {"a:f32", "a:f32,b:f32", "vp:f32,vs:f32,rho:f32", "a:u8,b:f32,c:f64",
                           "vp:f32,vs:f32,rho:f32,qp:f32,qs:f32", "a:f64,b:f64,c:f64"}) {
    const PackedShape shape = PackedShape::of(4096, KeyKind::kOctant, schema_of(text));
    const uint32_t w = shape.payload;
    const size_t limit = shape.page_size / w;  // the most rows a dictionary takes
    auto rows_from = [&](size_t distinct, const std::function<size_t(size_t)>& pick) {
      std::vector<std::byte> pool(distinct * w), v(n * w);
      for (std::byte& b : pool) b = std::byte(rng() & 0xff);
      for (size_t i = 0; i < n; ++i) std::copy_n(pool.begin() + pick(i) * w, w, v.begin() + i * w);
      return v;
    };
    struct Pattern {
      const char* name;
      std::vector<std::byte> vals;
    };
    std::vector<Pattern> patterns = {
        {"one row", rows_from(1, [](size_t) { return size_t{0}; })},
        {"alternating rows", rows_from(2, [](size_t i) { return i % 2; })},
        {"the dictionary's limit", rows_from(limit, [&](size_t i) { return i % limit; })},
        {"one row past it", rows_from(limit + 1, [&](size_t i) { return i % (limit + 1); })},
        {"repetitive, then noise",
         rows_from(n, [&](size_t i) { return i % 700 < 500 ? i % 3 : i; })},
    };
    std::vector<std::byte> odd(n * w);  // special floats in runs, in every 4-byte lane
    for (size_t i = 0; i < n; ++i) {
      for (uint32_t b = 0; b + 4 <= w; b += 4) {
        const uint32_t bits = specials[(i / 7 + b / 4) % std::size(specials)];
        std::memcpy(&odd[i * w + b], &bits, 4);
      }
      for (uint32_t b = w / 4 * 4; b < w; ++b) odd[i * w + b] = std::byte(i / 11 & 0xff);
    }
    patterns.push_back({"+0.0, -0.0, NaNs, denormals, infinities", odd});
    for (const Pattern& p : patterns) {
      SCOPED_TRACE(std::string(text) + ": " + p.name);
      e.vals = p.vals;
      pack_and_check(shape, e, rng);
      if (HasFailure()) return;
    }
  }
}

// Random damage to a packed page, column-wise or a row dictionary: readers
// may return garbage or refuse, but never read outside the page.
TEST(PackedLeaf, DamagedPagesNeverReadOutOfBounds) {
  for (const bool dictionary : {false, true}) {
    SCOPED_TRACE(dictionary ? "row dictionary" : "columns");
    std::mt19937_64 rng(5);
    const PackedShape shape = PackedShape::of(512, KeyKind::kOctant, schema_of("a:u32,b:u8"));
    Entries e;
    octree_leaves({0, 0, 0, 0}, rng, {2, 8, 0.3, 0.05}, &e.keys);
    e.vals = dictionary ? pooled_payloads(rng, e.keys.size(), shape.payload, 5)
                        : payloads(rng, e.keys.size(), shape.payload);
    PackedLeafBuilder b(shape);
    b.add_range(e.keys.data(), e.vals.data(), 0, static_cast<uint32_t>(e.keys.size()));
    // An exact-size heap copy, so that the sanitizers see any read past the end.
    std::vector<std::byte> good(shape.page_size);
    b.encode(good.data());
    int refused = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      auto bad = std::make_unique<std::byte[]>(shape.page_size);
      std::copy(good.begin(), good.end(), bad.get());
      for (int flips = 1 + static_cast<int>(rng() % 4); flips > 0; --flips) {
        bad[kPgCount + rng() % (shape.page_size - kPgCount)] = std::byte(rng() & 0xff);
      }
      PackedLeaf leaf;
      if (!leaf.open(bad.get(), shape)) {
        ++refused;
        continue;
      }
      std::vector<uint64_t> keys(leaf.size() + 1);
      std::vector<std::byte> vals((leaf.size() + 1) * size_t{shape.payload});
      if (!leaf.decode(keys.data(), vals.data())) ++refused;
      uint32_t pos = 0;
      uint64_t k = 0;
      if (leaf.size() > 0) {
        const uint32_t i = static_cast<uint32_t>(rng() % leaf.size());
        if (!leaf.bound(rng(), rng() % 2, &pos) || !leaf.key(i, &k)) ++refused;
        leaf.payload(i, vals.data());
      }
    }
    EXPECT_GT(refused, 0) << "some damage must be caught by the layout checks";
    EXPECT_EQ(static_cast<int>(good[19]), dictionary ? 1 : 0);
  }
}

// Mode 1's keys are successor() chained over the residuals, whatever the
// bits: block_keys takes a shorter path where no key is of level 20 or the
// root and no subtree reaches the root's end, and must agree with the chain
// everywhere, on damaged or crafted blocks too.
TEST(PackedLeaf, SuccessorBlocksDecodeAsTheChainOfSuccessors) {
  std::mt19937_64 rng(11);
  const PackedShape shape = PackedShape::of(4096, KeyKind::kOctant, schema_of(""));
  std::vector<uint64_t> keys;
  octree_leaves({0, 0, 0, 0}, rng, {3, 9, 0.3, 0}, &keys);
  PackedLeafBuilder b(shape);
  ASSERT_GT(b.add_range(keys.data(), nullptr, 0, static_cast<uint32_t>(keys.size())), 64u);
  std::vector<std::byte> good(shape.page_size);
  b.encode(good.data());
  const uint32_t m = load16(good.data() + packed::kPgBlocks);
  std::byte* const blocks_at = good.data() + packed::kFieldsStart + 8 * size_t{m};
  const size_t bits_at = packed::kFieldsStart + 12 * size_t{m};
  int level_20 = 0, root = 0, root_end = 0, compared = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<std::byte> page = good;
    std::byte* bases = page.data() + packed::kFieldsStart;
    std::byte* blocks = page.data() + (blocks_at - good.data());
    for (size_t i = bits_at; i + kPackedSlack < page.size(); ++i) page[i] = std::byte(rng() & 0xff);
    for (uint32_t j = 0; j < m; ++j) {
      // The residuals' width (the last block's is kept: open() checks it).
      if (j + 1 < m) blocks[4 * size_t{j} + 2] = std::byte(rng() % 12);
      blocks[4 * size_t{j} + 3] = std::byte(packed::kModeSuccessor);
      // Bases of every kind: the root, level 20, near the root's end, any.
      const uint64_t r = rng(), slot = rng() % 28;
      const uint64_t high = trial % 3 == 0 ? ~uint64_t{0} << (7 + rng() % 8) : r;
      store64(bases + 8 * size_t{j}, (high & ~uint64_t{127}) | (trial % 5 == 0 ? 0 : slot));
    }
    PackedLeaf leaf;
    ASSERT_TRUE(leaf.open(page.data(), shape));
    for (uint32_t j = 0; j < m; ++j) {
      uint64_t got[kPackedBlock];
      uint32_t cnt = 0;
      if (!leaf.block_keys(j, got, &cnt)) continue;
      const std::byte* bits = page.data() + bits_at + load16(blocks + 4 * size_t{j});
      const uint32_t w = static_cast<uint32_t>(blocks[4 * size_t{j} + 2]);
      uint64_t k = load64(bases + 8 * size_t{j});
      ASSERT_EQ(got[0], k);
      for (uint32_t i = 1; i < cnt; ++i) {
        level_20 += (k & 127) >= kKeyLevel20Slot;
        root += (k & 127) == 0;
        root_end += packed::successor(k) == UINT64_MAX;
        k = packed::successor(k) + packed::read_bits(bits, uint64_t{i - 1} * w, w);
        ASSERT_EQ(got[i], k) << "block " << j << ", key " << i;
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 10000);
  EXPECT_GT(level_20, 0);
  EXPECT_GT(root, 0);
  EXPECT_GT(root_end, 0);
}

}  // namespace
}  // namespace weaver::page
