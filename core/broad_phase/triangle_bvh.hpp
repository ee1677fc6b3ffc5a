#pragma once
// A bounding-volume hierarchy of one object's triangle boxes, rebuilt every frame, for the
// feature-level candidate search of Stage III: which triangles' boxes come within a bound of
// a query box (the paper's expanded-AABB overlap test, without scanning every triangle).
#include "core/broad_phase/aabb.hpp"

#include <algorithm>
#include <array>
#include <functional>
#include <limits>
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
  void query(const AABB& query, const Bound& bound, const Visit& visit) const {
    this->query(query, bound, visit, [](std::int32_t) { return false; });
  }
  /// The same, without entering a subtree for which skip(node index) is true.
  template <typename Bound, typename Visit, typename Skip>
  void query(const AABB& query, const Bound& bound, const Visit& visit, const Skip& skip) const;

  /// Per node, the vertices that every triangle of its subtree uses (at most 3, ascending,
  /// kNoIndex after the last), given the triangles' faces: a search for a triangle f can skip
  /// a subtree holding one of f's vertices, all of whose triangles are then adjacent to f (the
  /// triangles around a vertex used by thousands of them overlap each other's boxes there).
  std::vector<std::array<Index, 3>> node_common_vertices(const std::vector<Face>& faces) const;
  /// Whether face f uses one of a node's common vertices (a node_common_vertices() entry):
  /// then every triangle of the node's subtree is adjacent to f.
  static bool adjacent_subtree(const std::array<Index, 3>& common, const Face& f) {
    for (const Index v : common)
      if (v != kNoIndex && (v == f[0] || v == f[1] || v == f[2])) return true;
    return false;
  }

  bool empty() const { return nodes_.empty(); }
  /// The box of a node (the union of its triangles' boxes), by the index skip() receives.
  const AABB& node_box(std::int32_t node) const { return nodes_[static_cast<size_t>(node)].box; }

  /// Per node, the largest triangle id in its subtree: a search that pairs f only with
  /// triangles of larger id (each unordered pair once) can pass over a subtree whose largest
  /// id is at most f.
  std::vector<Index> node_max_ids() const;

  /// The union, per node, of another box per triangle (`boxes[t]`, e.g. the triangles' boxes
  /// at one end of a CCD step), indexed as the nodes are for query_overlaps().
  std::vector<AABB> node_unions(const std::vector<AABB>& boxes) const;

  /// Calls visit(t) for every triangle t whose box overlaps `query` (closed boxes), without
  /// entering a subtree for which skip(node index) is true.
  template <typename Skip, typename Visit>
  void query_overlaps(const AABB& query, const Skip& skip, const Visit& visit) const;

  /// Whether some triangle's box lies within `bound` of `query` (squared box distance at most
  /// bound^2); stops at the first.
  bool any_within(const AABB& query, double bound) const {
    if (nodes_.empty()) return false;
    const double b2 = bound * bound;
    std::int32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[static_cast<size_t>(stack[--top])];
      if (box_distance_squared(query, node.box) > b2) continue;
      if (node.count > 0) {
        for (std::int32_t k = node.first; k < node.first + node.count; ++k)
          if (box_distance_squared(query, leaf_boxes_[static_cast<size_t>(k)]) <= b2) return true;
        continue;
      }
      stack[top++] = node.first + 1;
      stack[top++] = node.first;
    }
    return false;
  }

  class BestFirst;

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

template <typename Bound, typename Visit, typename Skip>
void TriangleBvh::query(const AABB& q, const Bound& bound, const Visit& visit, const Skip& skip) const {
  if (nodes_.empty()) return;
  std::int32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::int32_t at = stack[--top];
    const Node& node = nodes_[static_cast<size_t>(at)];
    double b = bound();
    if (box_distance_squared(q, node.box) > b * b || skip(at)) continue;
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

template <typename Skip, typename Visit>
void TriangleBvh::query_overlaps(const AABB& q, const Skip& skip, const Visit& visit) const {
  if (nodes_.empty()) return;
  std::int32_t stack[64];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::int32_t at = stack[--top];
    const Node& node = nodes_[static_cast<size_t>(at)];
    if (!boxes_overlap(q, node.box) || skip(at)) continue;
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k)
        if (boxes_overlap(q, leaf_boxes_[static_cast<size_t>(k)])) visit(order_[static_cast<size_t>(k)]);
      continue;
    }
    stack[top++] = node.first + 1;
    stack[top++] = node.first;
  }
}

/// Best-first search of query boxes ("probes") against triangle hierarchies: run() expands
/// (probe, node) entries in nondecreasing squared box distance over all probes added so far,
/// while that distance is within bound(), which is re-read before each step (visit may lower
/// it). A leaf's triangles are visited when the leaf comes up, each whose box is within the
/// bound at that moment; so once the bound has come down to an answer d, no leaf farther than
/// d is opened and no pair whose boxes are farther apart than d is visited. (Visiting a leaf's
/// triangles at once, rather than queueing each, halves the queue's traffic at the cost of a
/// few tests beyond the strict order.) Probes may be added between runs: a caller that adds
/// them in nondecreasing order of a lower bound L on their boxes' distances and runs up to L
/// before each addition keeps the global order. Equal distances are taken by probe number, then
/// node, so the search is deterministic. clear() keeps the allocations.
class TriangleBvh::BestFirst {
 public:
  void clear() {
    probes_.clear();
    heap_.clear();
  }
  /// Adds a probe (query box `box` into `bvh`) unless its root is farther than `bound`;
  /// returns its index either way (probes are numbered in the order added).
  std::size_t add(const TriangleBvh& bvh, const AABB& box, double bound) {
    const std::size_t p = probes_.size();
    probes_.push_back({&bvh, box});
    if (!bvh.nodes_.empty()) {
      const double d2 = box_distance_squared(box, bvh.nodes_[0].box);
      if (d2 <= bound * bound) push({d2, static_cast<std::int32_t>(p), 0});
    }
    return p;
  }
  /// Visits pairs as described above, stopping at the first entry beyond bound() or beyond
  /// `until_d2` (squared); visit(probe, triangle, squared box distance). Entries of a probe
  /// for which keep(probe) has become false are dropped unexpanded (e.g. a probe that can no
  /// longer improve the answer).
  template <typename Bound, typename Keep, typename Visit>
  void run(const Bound& bound, const Keep& keep, const Visit& visit,
           double until_d2 = std::numeric_limits<double>::infinity());

 private:
  struct Probe {
    const TriangleBvh* bvh;
    AABB box;
  };
  struct Entry {
    double d2;
    std::int32_t probe;
    std::int32_t node;
    /// Ties by probe (a caller numbering its probes in a useful order, e.g. by triangle id
    /// for a tie-break on ids, gets that order among equal distances), then by node.
    bool operator>(const Entry& o) const {
      return d2 != o.d2 ? d2 > o.d2 : probe != o.probe ? probe > o.probe : node > o.node;
    }
  };
  void push(const Entry& e) {
    heap_.push_back(e);
    std::push_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
  }
  std::vector<Probe> probes_;
  std::vector<Entry> heap_;
};

template <typename Bound, typename Keep, typename Visit>
void TriangleBvh::BestFirst::run(const Bound& bound, const Keep& keep, const Visit& visit,
                                 double until_d2) {
  while (!heap_.empty()) {
    const double b = bound();
    const Entry e = heap_.front();
    if (e.d2 > b * b || e.d2 > until_d2) return;
    std::pop_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
    heap_.pop_back();
    if (!keep(static_cast<std::size_t>(e.probe))) continue;
    const Probe& probe = probes_[static_cast<std::size_t>(e.probe)];
    const TriangleBvh& bvh = *probe.bvh;
    const Node& node = bvh.nodes_[static_cast<std::size_t>(e.node)];
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const double d2 = box_distance_squared(probe.box, bvh.leaf_boxes_[static_cast<std::size_t>(k)]);
        const double bk = bound();
        if (d2 <= bk * bk) visit(static_cast<std::size_t>(e.probe), bvh.order_[static_cast<std::size_t>(k)], d2);
      }
      continue;
    }
    auto offer = [&](const AABB& box, std::int32_t child) {
      const double d2 = box_distance_squared(probe.box, box);
      if (d2 <= b * b) push({d2, e.probe, child});
    };
    offer(bvh.nodes_[static_cast<std::size_t>(node.first)].box, node.first);
    offer(bvh.nodes_[static_cast<std::size_t>(node.first + 1)].box, node.first + 1);
  }
}

}  // namespace vproxq
