#include "core/broad_phase/triangle_bvh.hpp"

#include <algorithm>
#include <limits>
#include <numeric>

namespace vproxq {

void TriangleBvh::build(const std::vector<AABB>& boxes) {
  nodes_.clear();
  node_min_ids_.clear();
  order_.resize(boxes.size());
  std::iota(order_.begin(), order_.end(), 0);
  leaf_boxes_.clear();
  if (boxes.empty()) return;
  std::vector<Vec3> centroids(boxes.size());
  for (size_t t = 0; t < boxes.size(); ++t) centroids[t] = boxes[t].center();
  nodes_.reserve(2 * boxes.size() / kLeafSize + 2);
  nodes_.push_back({});
  build_node(0, 0, static_cast<std::int32_t>(boxes.size()), boxes, centroids);
  leaf_boxes_.resize(order_.size());
  for (size_t k = 0; k < order_.size(); ++k) leaf_boxes_[k] = boxes[static_cast<size_t>(order_[k])];
  node_min_ids_.assign(nodes_.size(), std::numeric_limits<Index>::max());
  // Children come after their parent in nodes_, so a reverse pass sees them first.
  for (size_t n = nodes_.size(); n-- > 0;) {
    const Node& node = nodes_[n];
    Index& least = node_min_ids_[n];
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k)
        least = std::min(least, order_[static_cast<size_t>(k)]);
    } else {
      least = std::min(node_min_ids_[static_cast<size_t>(node.first)], node_min_ids_[static_cast<size_t>(node.first) + 1]);
    }
  }
}

std::vector<double> TriangleBvh::node_min(const std::vector<double>& value) const {
  std::vector<double> out(nodes_.size(), std::numeric_limits<double>::infinity());
  for (size_t n = nodes_.size(); n-- > 0;) {  // children first, as above
    const Node& node = nodes_[n];
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k)
        out[n] = std::min(out[n], value[static_cast<size_t>(order_[static_cast<size_t>(k)])]);
    } else {
      out[n] = std::min(out[static_cast<size_t>(node.first)], out[static_cast<size_t>(node.first) + 1]);
    }
  }
  return out;
}

std::vector<AABB> TriangleBvh::node_unions(const std::vector<AABB>& boxes) const {
  std::vector<AABB> out(nodes_.size());
  // Children come after their parent in nodes_, so a reverse pass sees them first.
  for (size_t n = nodes_.size(); n-- > 0;) {
    const Node& node = nodes_[n];
    AABB box;
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k)
        box.extend(boxes[static_cast<size_t>(order_[static_cast<size_t>(k)])]);
    } else {
      box = out[static_cast<size_t>(node.first)];
      box.extend(out[static_cast<size_t>(node.first) + 1]);
    }
    out[n] = box;
  }
  return out;
}

std::vector<std::array<Index, 3>> TriangleBvh::node_common_vertices(const std::vector<Face>& faces) const {
  constexpr std::array<Index, 3> kNone{kNoIndex, kNoIndex, kNoIndex};
  // The vertices of `a` that `keep` also holds, ascending.
  auto intersect = [](const std::array<Index, 3>& a, auto&& keep) {
    std::array<Index, 3> out{kNoIndex, kNoIndex, kNoIndex};
    int n = 0;
    for (Index v : a)
      if (v != kNoIndex && keep(v)) out[static_cast<size_t>(n++)] = v;
    return out;
  };
  auto holds = [](const std::array<Index, 3>& a, Index v) { return a[0] == v || a[1] == v || a[2] == v; };
  std::vector<std::array<Index, 3>> out(nodes_.size(), kNone);
  // Children come after their parent in nodes_, so a reverse pass sees them first.
  for (size_t n = nodes_.size(); n-- > 0;) {
    const Node& node = nodes_[n];
    std::array<Index, 3> common;
    if (node.count > 0) {
      std::array<Index, 3> first = faces[static_cast<size_t>(order_[static_cast<size_t>(node.first)])];
      std::sort(first.begin(), first.end());
      first = intersect(first, [&, prev = kNoIndex](Index v) mutable {  // distinct vertices only
        const bool fresh = v != prev;
        prev = v;
        return fresh;
      });
      common = first;
      for (std::int32_t k = node.first + 1; k < node.first + node.count; ++k) {
        const Face& f = faces[static_cast<size_t>(order_[static_cast<size_t>(k)])];
        common = intersect(common, [&](Index v) { return holds(f, v); });
      }
    } else {
      const auto& right = out[static_cast<size_t>(node.first) + 1];
      common = intersect(out[static_cast<size_t>(node.first)], [&](Index v) { return holds(right, v); });
    }
    out[n] = common;
  }
  return out;
}

// Depth stays below 64 (the query stack size): each split halves the range, and ranges of at
// most kLeafSize are leaves, so depth <= log2(2^31) + 1.
void TriangleBvh::build_node(std::int32_t slot, std::int32_t begin, std::int32_t end,
                             const std::vector<AABB>& boxes, const std::vector<Vec3>& centroids) {
  Node node;
  for (std::int32_t k = begin; k < end; ++k) node.box.extend(boxes[static_cast<size_t>(order_[static_cast<size_t>(k)])]);
  if (end - begin <= kLeafSize) {
    node.first = begin;
    node.count = end - begin;
    nodes_[static_cast<size_t>(slot)] = node;
    return;
  }
  AABB cb;
  for (std::int32_t k = begin; k < end; ++k) cb.extend(centroids[static_cast<size_t>(order_[static_cast<size_t>(k)])]);
  int axis = 0;
  const Vec3 ext = cb.hi - cb.lo;
  if (ext.y() > ext[axis]) axis = 1;
  if (ext.z() > ext[axis]) axis = 2;
  const std::int32_t mid = begin + (end - begin) / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end, [&](Index a, Index b) {
    const double ca = centroids[static_cast<size_t>(a)][axis], cbv = centroids[static_cast<size_t>(b)][axis];
    return ca < cbv || (ca == cbv && a < b);
  });
  // Children are an adjacent pair, allocated before recursing.
  const std::int32_t left = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back({});
  nodes_.push_back({});
  node.first = left;
  node.count = 0;
  nodes_[static_cast<size_t>(slot)] = node;
  build_node(left, begin, mid, boxes, centroids);
  build_node(left + 1, mid, end, boxes, centroids);
}

}  // namespace vproxq
