#include "schema/morton.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "reference/octant_reference.h"
#include "test_util.h"

namespace weaver {
namespace {

TEST(Morton, MatchesReferenceExhaustivelyOnSmallCoordinates) {
  for (uint32_t x = 0; x < 32; ++x)
    for (uint32_t y = 0; y < 32; ++y)
      for (uint32_t z = 0; z < 32; ++z) {
        const uint64_t code = morton_encode(x, y, z);
        ASSERT_EQ(code, reference::morton_encode(x, y, z));
        ASSERT_EQ(morton_decode(code), (Coord{x, y, z}));
      }
}

TEST(Morton, MatchesReferenceOnRandomCoordinates) {
  std::mt19937_64 rng(1);
  const uint64_t n = testing::scaled(2'000'000, 200'000);
  for (uint64_t i = 0; i < n; ++i) {
    const uint32_t x = rng() & kMortonAxisMask, y = rng() & kMortonAxisMask,
                   z = rng() & kMortonAxisMask;
    const uint64_t code = morton_encode(x, y, z);
    ASSERT_EQ(code, reference::morton_encode(x, y, z));
    const uint64_t any = rng() >> 1;  // any 63-bit code
    ASSERT_EQ(morton_decode(any), reference::morton_decode(any));
  }
}

// Both ways of interleaving (the shifts, and BMI2's PDEP and PEXT where the
// processor has them, whether or not this process chose them) against the
// reference.
TEST(Morton, ShiftsAndBitDepositBothMatchTheReference) {
  std::mt19937_64 rng(3);
  const bool deposit = morton_detail::has_bit_deposit();
  std::printf("BMI2 %s; this process interleaves with %s\n", deposit ? "present" : "absent",
              morton_detail::kFastBitDeposit ? "PDEP and PEXT" : "shifts");
  const uint64_t n = testing::scaled(1'000'000, 100'000);
  for (uint64_t i = 0; i < n; ++i) {
    const uint32_t c[3] = {uint32_t(rng() & kMortonAxisMask), uint32_t(rng() & kMortonAxisMask),
                           uint32_t(rng() & kMortonAxisMask)};
    const uint64_t code = reference::morton_encode(c[0], c[1], c[2]);
    const uint64_t any = rng() >> 1;
    const Coord back = reference::morton_decode(any);
    const uint32_t back_axis[3] = {back.x, back.y, back.z};
    uint64_t shifted = 0;
    for (int a = 0; a < 3; ++a) {
      shifted |= morton_detail::spread3(c[a]) << a;
      ASSERT_EQ(morton_detail::compact3(any >> a), back_axis[a]);
    }
    ASSERT_EQ(shifted, code);
#ifdef WEAVER_BIT_DEPOSIT
    if (!deposit) continue;
    uint64_t deposited = 0;
    for (int a = 0; a < 3; ++a) {
      deposited |= morton_detail::deposit_bits(c[a], morton_detail::kAxisBits << a);
      ASSERT_EQ(morton_detail::extract_bits(any, morton_detail::kAxisBits << a), back_axis[a]);
    }
    ASSERT_EQ(deposited, code);
#endif
  }
}

TEST(Morton, EncodesTheFarSideOfTheRoot) {
  const uint32_t far = 1u << 20;
  EXPECT_EQ(morton_decode(morton_encode(far, far, far)), (Coord{far, far, far}));
  EXPECT_EQ(morton_encode(far, 0, 0), uint64_t{1} << 60);
  EXPECT_EQ(morton_encode(0, 0, far), uint64_t{1} << 62);
}

// morton_step and morton_step_back against decoding, moving and encoding.
TEST(Morton, StepsMoveOneAxisByAPowerOfTwoEitherWay) {
  std::mt19937_64 rng(2);
  const uint64_t n = testing::scaled(1'000'000, 100'000);
  for (uint64_t i = 0; i < n; ++i) {
    const int axis = static_cast<int>(rng() % 3), bit = static_cast<int>(rng() % 21);
    const bool back = rng() % 2;
    uint32_t c[3] = {static_cast<uint32_t>(rng() & kMortonAxisMask),
                     static_cast<uint32_t>(rng() & kMortonAxisMask),
                     static_cast<uint32_t>(rng() & kMortonAxisMask)};
    if (rng() % 2) c[axis] &= ~((1u << bit) - 1);  // aligned, as octant corners are
    if (back ? c[axis] < (1u << bit) : uint64_t{c[axis]} + (1u << bit) > kMortonAxisMask) continue;
    const uint64_t code = reference::morton_encode(c[0], c[1], c[2]);
    if (back) {
      c[axis] -= 1u << bit;
      ASSERT_EQ(morton_step_back(code, axis, bit), reference::morton_encode(c[0], c[1], c[2]));
    } else {
      c[axis] += 1u << bit;
      ASSERT_EQ(morton_step(code, axis, bit), reference::morton_encode(c[0], c[1], c[2]));
    }
  }
  const uint32_t far = 1u << 20;
  EXPECT_EQ(morton_step(morton_encode(far - 1, 0, 0), 0, 0), morton_encode(far, 0, 0));
  EXPECT_EQ(morton_step_back(morton_encode(far, 0, 0), 0, 0), morton_encode(far - 1, 0, 0));
}

}  // namespace
}  // namespace weaver
