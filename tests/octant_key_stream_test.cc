// The wire form of sorted octant keys (util/octant_key_stream.h): every
// sequence of increasing valid keys comes back as it went, at every level
// and across levels; bytes it did not write are refused, not misread.
#include "util/octant_key_stream.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace weaver {
namespace {

bool decode(const std::string& bytes, std::vector<uint64_t>* keys) {
  keys->clear();
  return decode_octant_keys(bytes, keys);
}

// Random valid octants of every level, corners at the root's far edges too.
std::vector<uint64_t> random_keys(uint64_t seed, size_t n) {
  std::mt19937_64 rng(seed);
  std::vector<uint64_t> keys;
  for (size_t i = 0; i < n; ++i) {
    const int level = static_cast<int>(rng() % (kMaxLevel + 1));
    const uint32_t cells = uint32_t{1} << level, edge = uint32_t{1} << (kMaxLevel - level);
    auto coord = [&] { return static_cast<uint32_t>(rng() % 4 == 0 ? cells - 1 : rng() % cells); };
    keys.push_back(
        octant_key({coord() * edge, coord() * edge, coord() * edge, static_cast<uint8_t>(level)}));
  }
  keys.push_back(octant_key(octant_root()));
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  return keys;
}

TEST(OctantKeyStream, IncreasingKeysRoundTripAtEveryLevel) {
  for (uint64_t seed : {1, 2, 3, 4}) {
    const std::vector<uint64_t> keys = random_keys(seed, 20000);
    std::vector<uint64_t> back;
    ASSERT_TRUE(decode(encode_octant_keys(keys), &back));
    EXPECT_EQ(back, keys);
  }
}

// An octant and its descendants (same Morton code, later levels) and the
// deepest octants (level 20, whose keys hold the Morton code's low bits).
TEST(OctantKeyStream, AncestorsAndFinestOctantsRoundTrip) {
  std::vector<uint64_t> keys;
  Octant o = octant_root();
  for (int l = 0; l < kMaxLevel; ++l) {
    keys.push_back(octant_key(o));
    o = octant_child(o, 7);
  }
  for (int c = 0; c < 8; ++c) keys.push_back(octant_key(octant_child(octant_parent(o), c)));
  std::sort(keys.begin(), keys.end());
  std::vector<uint64_t> back;
  ASSERT_TRUE(decode(encode_octant_keys(keys), &back));
  EXPECT_EQ(back, keys);
}

// A surface of leaves costs a byte or two each, not the five of their keys'
// differences.
TEST(OctantKeyStream, AFaceOfLeavesTakesUnderTwoBytesALeaf) {
  std::vector<uint64_t> keys;
  const int level = 10;
  const uint32_t edge = uint32_t{1} << (kMaxLevel - level);
  for (uint32_t y = 0; y < 64; ++y) {
    for (uint32_t z = 0; z < 64; ++z) keys.push_back(octant_key({0, y * edge, z * edge, level}));
  }
  std::sort(keys.begin(), keys.end());
  const std::string bytes = encode_octant_keys(keys);
  EXPECT_LT(bytes.size(), 2 * keys.size());
  std::vector<uint64_t> back;
  ASSERT_TRUE(decode(bytes, &back));
  EXPECT_EQ(back, keys);
}

TEST(OctantKeyStream, BytesItDidNotWriteAreRefused) {
  std::vector<uint64_t> keys;
  std::string level21, past_root, cut_short;
  append_varint(level21, 21);                               // no level 21
  append_varint(past_root, (uint64_t{1} << 30) << 5 | 10);  // 2^30 cells of level 10
  cut_short = encode_octant_keys(random_keys(5, 100));
  cut_short.back() = static_cast<char>(0x80);  // a varint that never ends
  EXPECT_FALSE(decode(level21, &keys));
  EXPECT_FALSE(decode(past_root, &keys));
  EXPECT_FALSE(decode(cut_short, &keys));
}

}  // namespace
}  // namespace weaver
