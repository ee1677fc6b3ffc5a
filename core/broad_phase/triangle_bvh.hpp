#pragma once
// A bounding-volume hierarchy of one object's triangle boxes, rebuilt every frame, for the
// feature-level candidate search of Stage III: which triangles' boxes come within a bound of
// a query box (the paper's expanded-AABB overlap test, without scanning every triangle).
#include "core/broad_phase/aabb.hpp"

#include <vector>

namespace vproxq {

class TriangleBvh {
 public:
  /// Builds over `boxes` (triangle t has boxes[t]): median split on the longest axis of the
  /// centroids, up to kLeafSize triangles per leaf. Deterministic.
  void build(const std::vector<AABB>& boxes);

  /// Calls visit(t, squared box distance) for every triangle t whose box is within the bound
  /// of `query`, nearest subtrees first. `bound()` is re-read as the search goes (visit may
  /// lower it), so later subtrees are pruned against the current value.
  template <typename Bound, typename Visit>
  void query(const AABB& query, const Bound& bound, const Visit& visit) const;

  bool empty() const { return nodes_.empty(); }

 private:
  static constexpr int kLeafSize = 4;
  struct Node {
    AABB box;
    std::int32_t first;  ///< leaf: first index into order_; inner: left child (right = left+1)
    std::int32_t count;  ///< leaf: number of triangles; inner: 0
  };
  void build_node(std::int32_t slot, std::int32_t begin, std::int32_t end,
                  const std::vector<AABB>& boxes, const std::vector<Vec3>& centroids);
  std::vector<Node> nodes_;
  std::vector<Index> order_;
  std::vector<AABB> leaf_boxes_;  ///< boxes in order_ order
};

template <typename Bound, typename Visit>
void TriangleBvh::query(const AABB& q, const Bound& bound, const Visit& visit) const {
  if (nodes_.empty()) return;
  std::int32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[static_cast<size_t>(stack[--top])];
    double b = bound();
    if (box_distance_squared(q, node.box) > b * b) continue;
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const double d2 = box_distance_squared(q, leaf_boxes_[static_cast<size_t>(k)]);
        b = bound();
        if (d2 <= b * b) visit(order_[static_cast<size_t>(k)], d2);
      }
      continue;
    }
    const std::int32_t l = node.first, r = node.first + 1;
    const double dl = box_distance_squared(q, nodes_[static_cast<size_t>(l)].box);
    const double dr = box_distance_squared(q, nodes_[static_cast<size_t>(r)].box);
    // Push the farther child first so the nearer one is searched first.
    if (dl <= dr) {
      stack[top++] = r;
      stack[top++] = l;
    } else {
      stack[top++] = l;
      stack[top++] = r;
    }
  }
}

}  // namespace vproxq
