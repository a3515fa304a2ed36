// LeafWindow (queries', slices' and verify's window on a table) against the
// B+tree it reads: floors with their ranks and payloads, and gets, over
// plain and packed tables of many pages, for keys asked in runs near each
// other (as a sorted batch and verify ask them), far apart, between pages,
// below the first key and past the last; decoded pages and sparse lookups.
#include "db/leaf_window.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "storage/file.h"
#include "test_util.h"

namespace weaver {
namespace {

std::unique_ptr<BTree> table_of(const std::string& path, bool packed,
                                const std::vector<uint64_t>& keys) {
  std::unique_ptr<File> f;
  EXPECT_OK(open_posix_file(path, OpenMode::kCreateTruncate, &f));
  TableOptions o;
  o.page_size = 512;  // many leaves
  o.key_kind = KeyKind::kNode;
  std::string error;
  o.schema = *RecordSchema::parse("kind:u8", &error);
  o.packed = packed;
  std::unique_ptr<BTree> t;
  EXPECT_OK(BTree::create(std::move(f), o, 1 << 20, &t));
  std::vector<std::byte> payloads;
  for (uint64_t k : keys) payloads.push_back(static_cast<std::byte>(k * 7 % 251));
  EXPECT_OK(t->append_batch(keys.data(), payloads.data(), keys.size()));
  EXPECT_OK(t->commit());
  return t;
}

TEST(LeafWindow, AnswersAsTheTreeDoes) {
  testing::TempDir dir;
  std::mt19937_64 rng(23);
  for (const int mode : {0, 1, 2}) {
    const bool packed = mode > 0, sparse = mode == 2;
    std::vector<uint64_t> keys;
    uint64_t k = 1000;
    for (int i = 0; i < 60000; ++i) keys.push_back(k += 1 + rng() % (rng() % 50 == 0 ? 5000 : 9));
    auto t = table_of(dir.file(packed ? "packed" : "plain"), packed, keys);
    LeafWindow window(*t, true);
    uint64_t q = keys[0];
    int hits = 0;
    for (int i = 0; i < 300000; ++i) {
      switch (rng() % 10) {
        case 0: q = rng() % (keys.back() + 10000); break;  // anywhere, past the end too
        case 1: q = rng() % 1000; break;                   // below the first key
        default: q = q + rng() % 40 - (q >= 20 ? 20 : q);  // a walk near the last key
      }
      SCOPED_TRACE(std::string(packed ? "packed" : "plain") + (sparse ? ", sparse" : "") +
                   ", key " + std::to_string(q));
      window.set_sparse(sparse && rng() % 2 == 0);  // switching back and forth
      uint64_t want = 0, want_rank = 0;
      bool want_found = false, got_found = false;
      std::byte want_kind{};
      ASSERT_OK(t->floor(q, &want, &want_kind, &want_found));
      LeafWindow::Floor f;
      ASSERT_OK(window.floor(q, &f));
      ASSERT_EQ(f.found, want_found);
      if (want_found) {
        ASSERT_OK(t->rank(want, &want_rank));
        ASSERT_EQ(f.key, want);
        ASSERT_EQ(f.rank, want_rank);
        ASSERT_EQ(*f.payload, want_kind);
      }
      const std::byte* kind = nullptr;
      ASSERT_OK(t->get(q, &want_kind, &want_found));
      ASSERT_OK(window.get(q, &kind, &got_found));
      ASSERT_EQ(got_found, want_found);
      if (want_found) {
        ASSERT_EQ(*kind, want_kind);
        ++hits;
      }
    }
    EXPECT_GT(hits, 1000);
  }
}

}  // namespace
}  // namespace weaver
