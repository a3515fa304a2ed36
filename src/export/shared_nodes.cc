#include "export/shared_nodes.h"

namespace weaver {

Status SharedNodes::build(Mesh& mesh, const PartMap& parts, const std::string& scratch_dir,
                          uint64_t memory) {
  counts_.assign(parts.parts(), 0);
  if (mesh.node_count() >> kNodeBits) {
    return Status::InvalidArgument("more than 2^40 nodes: too many to share out by part");
  }
  ExternalSorter by_node(scratch_dir + "/by-node", memory / 2);
  ElementScan scan;
  WEAVER_RETURN_IF_ERROR(scan.start(mesh, 0, true));
  for (; scan.valid(); scan.next()) {
    uint32_t p = 0;
    WEAVER_RETURN_IF_ERROR(parts.part_of(scan.element().id, &p));
    for (uint64_t n : scan.element().nodes) WEAVER_RETURN_IF_ERROR(by_node.add({n, p}));
  }
  WEAVER_RETURN_IF_ERROR(scan.status());
  WEAVER_RETURN_IF_ERROR(by_node.finish());
  by_part_ = std::make_unique<ExternalSorter>(scratch_dir + "/by-part", memory / 2);
  std::vector<uint32_t> users;
  uint64_t node = UINT64_MAX;
  auto flush = [&]() -> Status {
    if (users.size() < 2) return Status::Ok();
    for (uint32_t q : users) {
      for (uint32_t r : users) {
        if (r == q) continue;
        WEAVER_RETURN_IF_ERROR(by_part_->add({(uint64_t{q} << kNodeBits) | node, r}));
        ++counts_[q];
      }
    }
    return Status::Ok();
  };
  for (;;) {
    KeyTag kt;
    bool done = false;
    WEAVER_RETURN_IF_ERROR(by_node.next(&kt, &done));
    if (done) break;
    if (kt.key != node) {
      WEAVER_RETURN_IF_ERROR(flush());
      node = kt.key;
      users.clear();
    }
    if (users.empty() || users.back() != kt.tag) users.push_back(uint32_t(kt.tag));
  }
  WEAVER_RETURN_IF_ERROR(flush());
  return by_part_->finish();
}

Status SharedNodes::next(uint32_t p, uint64_t* node, uint32_t* other) {
  KeyTag kt;
  bool done = false;
  WEAVER_RETURN_IF_ERROR(by_part_->next(&kt, &done));
  if (done || (kt.key >> kNodeBits) != p) {
    return Status::Internal("shared nodes of part " + std::to_string(p) + " read out of order");
  }
  *node = kt.key & ((uint64_t{1} << kNodeBits) - 1);
  *other = uint32_t(kt.tag);
  return Status::Ok();
}

}  // namespace weaver
