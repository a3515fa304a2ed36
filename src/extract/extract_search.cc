// The conventional, search-based extraction (paper, section 3), kept as the
// baseline users compare the bucket sort against:
//   1. a node B-tree keyed by node key; for every element vertex, a lookup and
//      an insert (or update) that records the element's code in the node's
//      payload (up to 8 codes: storage about e + 9n);
//   2. a pass over the node B-tree in key order that numbers the nodes and
//      classifies each from the codes of the elements touching it (their
//      directions, then NodeClassifier's aggregate hits for empty cells).
#include "extract/extract_search.h"

#include <cstring>

#include "extract/leaf_reader.h"
#include "extract/node_classifier.h"
#include "schema/node.h"
#include "schema/octant.h"

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

Status record_vertices(BTree& octants, BTree& scratch, ExtractResult* result) {
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

Status number_and_classify(BTree& octants, BTree& scratch, BTree& nodes, ExtractResult* result) {
  NodeClassifier classifier(octants);
  BTreeCursor c;
  WEAVER_RETURN_IF_ERROR(scratch.seek_cursor(0, &c));
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

}  // namespace

Status extract_by_search(BTree& octants, BTree& nodes, const std::string& scratch_path,
                         uint64_t pool_bytes, ExtractResult* result) {
  TableOptions o;
  o.key_kind = KeyKind::kNode;
  std::string error;
  o.schema = *RecordSchema::parse(kScratchSchema, &error);
  std::unique_ptr<File> f;
  WEAVER_RETURN_IF_ERROR(open_posix_file(scratch_path, OpenMode::kCreateTruncate, &f));
  std::unique_ptr<BTree> scratch;
  WEAVER_RETURN_IF_ERROR(BTree::create(std::move(f), o, pool_bytes, &scratch));
  Status st = record_vertices(octants, *scratch, result);
  if (st.ok()) st = scratch->commit();  // the node B-tree on disk, as in the paper
  if (st.ok()) result->search_tree_bytes = scratch->file_bytes();
  if (st.ok()) st = number_and_classify(octants, *scratch, nodes, result);
  scratch.reset();
  std::remove(scratch_path.c_str());
  return st;
}

}  // namespace weaver
