#include "model/material_merge.h"

#include <algorithm>

namespace weaver {

Status MaterialMerger::add(const Entry& e) {
  const Octant& o = e.octant;
  // The common case, the next sibling in the deepest open group: no group
  // closes (its coarser ones held its first member's ancestors, o's too).
  const Group& same = groups_[o.level];
  if (o.level > 0 && o.level == deepest_ && same.count > 0 && same.parent == octant_parent(o)) {
    return push(e);
  }
  // Pending groups that are not o's ancestors' sibling sets will never
  // complete: their parents' subtrees are behind us.
  for (int l = 1; l <= kMaxLevel; ++l) {
    Group& g = groups_[l];
    if (g.count == 0 && !g.broken) continue;
    if (l > o.level || !(g.parent == octant_ancestor(o, l - 1))) {
      WEAVER_RETURN_IF_ERROR(close_from(l));
      break;
    }
  }
  return push(e);
}

Status MaterialMerger::finish() { return close_from(0); }

Status MaterialMerger::push(const Entry& e) {
  const int l = e.octant.level;
  if (l == 0) return emit(e);  // the root has no siblings
  Group& g = groups_[l];
  if (g.broken) {
    WEAVER_RETURN_IF_ERROR(break_coarser(l, e.octant));
    return emit(e);
  }
  if (g.count == 0) g.parent = octant_parent(e.octant);
  g.members[g.count++] = e;
  deepest_ = std::max(deepest_, l);
  if (g.count < 8) return Status::Ok();
  if (!agree(g.members.data())) {
    WEAVER_RETURN_IF_ERROR(break_coarser(l, e.octant));
    for (const Entry& m : g.members) WEAVER_RETURN_IF_ERROR(emit(m));
    g.count = 0;
    g.broken = true;  // until the stream leaves this parent
    return Status::Ok();
  }
  const Entry parent = merged(g.parent, g.members.data());
  g.count = 0;
  g.broken = false;
  return push(parent);
}

MaterialMerger::Entry MaterialMerger::merged(const Octant& parent, const Entry* eight) const {
  Entry p{parent, {}, eight[0].low, eight[0].high};
  for (int f = 0; f < fields_; ++f) {
    double sum = 0;
    for (int i = 0; i < 8; ++i) {
      sum += eight[i].mean[f];
      p.low[f] = std::min(p.low[f], eight[i].low[f]);
      p.high[f] = std::max(p.high[f], eight[i].high[f]);
    }
    p.mean[f] = static_cast<float>(sum / 8);
  }
  return p;
}

bool MaterialMerger::agree(const Entry* eight) const {
  for (int f = 0; f < fields_; ++f) {
    float low = eight[0].low[f], high = eight[0].high[f];
    for (int i = 0; i < 8; ++i) {
      low = std::min(low, eight[i].low[f]);
      high = std::max(high, eight[i].high[f]);
    }
    if (tolerance_ == 0 ? high != low : high - low > tolerance_ * std::abs(low)) return false;
  }
  return true;
}

Status MaterialMerger::close_from(int level) {
  level = std::max(level, 1);
  deepest_ = std::min(deepest_, level - 1);
  for (int l = level; l <= kMaxLevel; ++l) {
    if (groups_[l].count > 0) {
      WEAVER_RETURN_IF_ERROR(break_coarser(level, groups_[l].members[0].octant));
      break;
    }
  }
  // The open groups form a chain, each inside the next coarser one's
  // parent after its members: coarsest first is key order.
  for (int l = level; l <= kMaxLevel; ++l) {
    Group& g = groups_[l];
    for (int i = 0; i < g.count; ++i) WEAVER_RETURN_IF_ERROR(emit(g.members[i]));
    g.count = 0;  // the members' slots are written before they are read again
    g.broken = false;
  }
  return Status::Ok();
}

Status MaterialMerger::break_coarser(int level, const Octant& finer) {
  deepest_ = std::max(deepest_, level - 1);
  for (int l = 1; l < level; ++l) {
    Group& g = groups_[l];
    for (int i = 0; i < g.count; ++i) WEAVER_RETURN_IF_ERROR(emit(g.members[i]));
    g.count = 0;
    g.broken = true;
    g.parent = octant_ancestor(finer, l - 1);
  }
  return Status::Ok();
}

Status MaterialMerger::emit(const Entry& e) {
  ++emitted_;
  return entry_sink_ ? entry_sink_(e) : sink_(octant_key(e.octant), e.mean);
}

}  // namespace weaver
