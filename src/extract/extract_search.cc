// The conventional, search-based extraction (paper, section 3), kept as the
// baseline users compare the bucket sort against:
//   1. a node B-tree keyed by node key; for every element vertex, a lookup and
//      an insert (or update) that records the element's code in the node's
//      payload (up to 8 codes: storage about e + 9n).  Or, to see what a
//      write-optimised store does to this baseline, an LSM store in its place;
//   2. a pass over the node B-tree in key order that numbers the nodes and
//      classifies each from the codes of the elements touching it (their
//      directions, then NodeClassifier's aggregate hits for empty cells).
#include "extract/extract_search.h"

#include <cstring>
#include <filesystem>

#include "db/leaf_reader.h"
#include "extract/node_classifier.h"
#include "schema/node.h"
#include "schema/octant.h"
#include "storage/lsm.h"

namespace weaver {
namespace {

constexpr int kMaxCodes = 8;
constexpr char kScratchSchema[] =
    "count:u8,c0:u64,c1:u64,c2:u64,c3:u64,c4:u64,c5:u64,c6:u64,c7:u64";
constexpr size_t kPayload = 1 + 8 * kMaxCodes;

// Which corner of element e the node n is.
int corner_index(const Octant& e, Coord n) {
  return (n.x > e.x ? 1 : 0) | (n.y > e.y ? 2 : 0) | (n.z > e.z ? 4 : 0);
}

Status record_vertices(BTree& octants, Store& scratch, ExtractResult* result) {
  LeafReader c;
  WEAVER_RETURN_IF_ERROR(c.open(octants));
  std::byte rec[kPayload];
  while (c.valid()) {
    const uint64_t code = c.key();
    const Octant e = octant_from_key(code);
    for (int k = 0; k < 8; ++k) {
      const uint64_t key = node_key(octant_corner(e, k));
      bool found = false;
      WEAVER_RETURN_IF_ERROR(scratch.get(key, rec, &found));
      uint8_t count = found ? static_cast<uint8_t>(rec[0]) : 0;
      if (count >= kMaxCodes) {
        return Status::Corruption("node touched by more than 8 elements: overlapping octants?");
      }
      if (!found) std::memset(rec, 0, sizeof rec);
      std::memcpy(rec + 1 + 8 * count, &code, 8);
      rec[0] = static_cast<std::byte>(count + 1);
      WEAVER_RETURN_IF_ERROR(scratch.put(key, rec, nullptr));
    }
    ++result->elements;
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

Status number_and_classify(BTree& octants, Store& scratch, BTree& nodes, int cache_bits,
                           ExtractResult* result) {
  NodeClassifier classifier(octants, cache_bits);
  std::unique_ptr<Cursor> cursor;
  WEAVER_RETURN_IF_ERROR(scratch.seek(0, &cursor));
  Cursor& c = *cursor;
  while (c.valid()) {
    const Coord n = morton_decode(c.key());
    const std::byte* rec = c.payload();
    uint8_t mask = 0;
    for (int i = 0; i < static_cast<int>(rec[0]); ++i) {
      uint64_t code;
      std::memcpy(&code, rec + 1 + 8 * i, 8);
      mask |= corner_direction_bit(corner_index(octant_from_key(code), n));
    }
    NodeKind kind = NodeKind::kAnchored;
    WEAVER_RETURN_IF_ERROR(classifier.classify(c.key(), mask, &kind));
    const std::byte payload{static_cast<uint8_t>(kind)};
    WEAVER_RETURN_IF_ERROR(nodes.append(c.key(), &payload));
    count_kind(kind, result);
    WEAVER_RETURN_IF_ERROR(c.next());
  }
  return Status::Ok();
}

TableOptions scratch_options() {
  TableOptions o;
  o.key_kind = KeyKind::kNode;
  std::string error;
  o.schema = *RecordSchema::parse(kScratchSchema, &error);
  return o;
}

// Both stores end on disk before the numbering pass, as the paper's node
// B-tree does: the B+tree committed, the LSM compacted (one run) and committed.
Status build_and_number(BTree& octants, Store& scratch, BTree& nodes, int cache_bits,
                        ExtractResult* result) {
  WEAVER_RETURN_IF_ERROR(record_vertices(octants, scratch, result));
  if (auto* lsm = dynamic_cast<LsmTree*>(&scratch)) {
    WEAVER_RETURN_IF_ERROR(lsm->compact());
    WEAVER_RETURN_IF_ERROR(lsm->commit());
    result->search_tree_bytes = lsm->file_bytes();
  } else {
    auto& tree = dynamic_cast<BTree&>(scratch);
    WEAVER_RETURN_IF_ERROR(tree.commit());
    result->search_tree_bytes = tree.file_bytes();
  }
  return number_and_classify(octants, scratch, nodes, cache_bits, result);
}

}  // namespace

Status extract_by_search(BTree& octants, BTree& nodes, const std::string& scratch_path,
                         uint64_t store_bytes, int cache_bits, bool lsm, ExtractResult* result) {
  Status st;
  if (lsm) {
    // Half the share to the memtable, half to the pools of its runs (at
    // most 16 of them at once).
    LsmOptions o;
    o.table = scratch_options();
    o.memtable_bytes = store_bytes / 2;
    o.run_pool_bytes = std::max<uint64_t>(store_bytes / 2 / 16, 1 << 16);
    std::unique_ptr<LsmTree> scratch;
    st = LsmTree::create(scratch_path + ".lsm", o, &scratch);
    if (st.ok()) st = build_and_number(octants, *scratch, nodes, cache_bits, result);
    scratch.reset();
    std::error_code ec;
    std::filesystem::remove_all(scratch_path + ".lsm", ec);
    return st;
  }
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(scratch_path + ".bt", OpenMode::kCreateTruncate, &f));
  std::unique_ptr<BTree> scratch;
  st = BTree::create(std::move(f), scratch_options(), store_bytes, &scratch);
  if (st.ok()) st = build_and_number(octants, *scratch, nodes, cache_bits, result);
  scratch.reset();
  std::remove((scratch_path + ".bt").c_str());
  return st;
}

}  // namespace weaver
