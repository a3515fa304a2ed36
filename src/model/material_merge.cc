#include "model/material_merge.h"

#include <algorithm>

namespace weaver {

Status MaterialMerger::add(const Octant& o, const ModelValues& v) {
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
  return push(Entry{o, v, v, v});
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
  if (g.count < 8) return Status::Ok();
  if (!agree(g)) {
    WEAVER_RETURN_IF_ERROR(break_coarser(l, e.octant));
    for (const Entry& m : g.members) WEAVER_RETURN_IF_ERROR(emit(m));
    g.count = 0;
    g.broken = true;  // until the stream leaves this parent
    return Status::Ok();
  }
  Entry parent{g.parent, {}, g.members[0].low, g.members[0].high};
  for (int f = 0; f < fields_; ++f) {
    double sum = 0;
    for (const Entry& m : g.members) {
      sum += m.mean[f];
      parent.low[f] = std::min(parent.low[f], m.low[f]);
      parent.high[f] = std::max(parent.high[f], m.high[f]);
    }
    parent.mean[f] = static_cast<float>(sum / 8);
  }
  g = Group{};
  return push(parent);
}

bool MaterialMerger::agree(const Group& g) const {
  for (int f = 0; f < fields_; ++f) {
    float low = g.members[0].low[f], high = g.members[0].high[f];
    for (const Entry& m : g.members) {
      low = std::min(low, m.low[f]);
      high = std::max(high, m.high[f]);
    }
    if (tolerance_ == 0 ? high != low : high - low > tolerance_ * std::abs(low)) return false;
  }
  return true;
}

Status MaterialMerger::close_from(int level) {
  level = std::max(level, 1);
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
    g = Group{};
  }
  return Status::Ok();
}

Status MaterialMerger::break_coarser(int level, const Octant& finer) {
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
  return sink_(octant_key(e.octant), e.mean);
}

}  // namespace weaver
