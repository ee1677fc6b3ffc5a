#pragma once
// A bounding-volume hierarchy of one object's triangle boxes, rebuilt every frame, for the
// feature-level candidate search of Stage III: which triangles' boxes come within a bound of
// a query box (the paper's expanded-AABB overlap test, without scanning every triangle).
#include "core/broad_phase/aabb.hpp"
#include "core/geometry/diagonals.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace vproxq {

class TriangleBvh {
 public:
  /// Builds over `boxes` (triangle t has boxes[t]): median split on the longest axis of the
  /// centroids, up to kLeafSize triangles per leaf. Deterministic: with `threads` > 1 the
  /// subtrees below the top levels are built in parallel, into the same nodes at the same
  /// places (a subtree's place follows from the sizes of the ranges before it).
  void build(const std::vector<AABB>& boxes, int threads = 1);

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
  /// Number of nodes; node indices run from 0 (the root) to node_count() - 1.
  std::int32_t node_count() const { return static_cast<std::int32_t>(nodes_.size()); }
  /// The box of a node (the union of its triangles' boxes), by the index skip() receives.
  const AABB& node_box(std::int32_t node) const { return nodes_[static_cast<size_t>(node)].box; }

  /// The union, per node, of another box per triangle (`boxes[t]`, e.g. the triangles' boxes
  /// at one end of a CCD step), indexed as the nodes are for query_overlaps().
  std::vector<AABB> node_unions(const std::vector<AABB>& boxes) const;

  /// Calls visit(t) for every triangle t whose box overlaps `query` (closed boxes), without
  /// entering a subtree for which skip(node index) is true; in the subtree of node `from`
  /// (the root by default) only.
  template <typename Skip, typename Visit>
  void query_overlaps(const AABB& query, const Skip& skip, const Visit& visit, std::int32_t from = 0) const;

  /// Whether a node (an index as skip() receives) is a leaf.
  bool is_leaf(std::int32_t node) const { return nodes_[static_cast<size_t>(node)].count > 0; }
  /// Calls visit(t) for the triangles of a leaf, in their order in the hierarchy.
  template <typename Visit>
  void for_each_leaf_triangle(std::int32_t leaf, const Visit& visit) const {
    const Node& node = nodes_[static_cast<size_t>(leaf)];
    for (std::int32_t k = node.first; k < node.first + node.count; ++k) visit(order_[static_cast<size_t>(k)]);
  }

  /// A pair of nodes of one hierarchy: the same node (the pairs within its subtree), or two
  /// nodes neither of which lies in the other's subtree (the pairs across them).
  using NodePair = std::array<std::int32_t, 2>;
  /// Calls visit(t, u) once for every unordered pair of distinct triangles of the node pair
  /// (a, b) whose boxes overlap (closed boxes), descending both subtrees together: a pair of
  /// nodes whose boxes overlap is split (the one with the larger box; within one node, into
  /// its children's three pairs), without entering a pair (x, y) for which skip(x, y) is true
  /// (x == y: the pairs within x). Within one object, this replaces a search per triangle:
  /// neighbouring triangles share the upper levels (docs/algorithms.md, "Continuous collision detection").
  template <typename Skip, typename Visit>
  void self_overlaps(const NodePair& pair, const Skip& skip, const Visit& visit) const;
  /// The node pairs that self_overlaps() from the root, (0, 0), goes through first, expanded
  /// (as it does, with the same skip) until each pair holds at most `max_triangles` triangles
  /// in all or is a single leaf: running self_overlaps() on each of them visits what it visits
  /// from the root, so they are units of parallel work. Empty for an empty hierarchy.
  template <typename Skip>
  std::vector<NodePair> self_overlap_pairs(std::int32_t max_triangles, const Skip& skip) const {
    return self_pairs_below(max_triangles, overlap_test(skip));
  }

  /// The descent of self_overlaps() with another test: from the node pair `start`, enters a
  /// pair (x, y) only where enter(x, y) is true (x == y: the pairs within x), splitting it as
  /// self_overlaps() does, and calls visit(t, u, box of t, box of u) once for every unordered
  /// pair of distinct triangles of each pair of leaves it enters (a leaf with itself
  /// included), whatever their boxes.
  template <typename Enter, typename Visit>
  void descend_self(const NodePair& start, const Enter& enter, const Visit& visit) const;
  /// The descent of descend_self() from `start`, entering a pair (x, y) only where enter(x, y)
  /// is true, that hands each entered pair to take(x, y) and splits it as descend_self() does
  /// unless take() returns true (it has dealt with the pair's triangle pairs). take() must
  /// return true for a pair with a leaf in it (a leaf with itself included): those are not
  /// split.
  template <typename Enter, typename Take>
  void descend_self_until(const NodePair& start, const Enter& enter, const Take& take) const {
    if (nodes_.empty()) return;
    thread_local std::vector<NodePair> stack;  // reused: called per unit of work
    walk_self(start, stack, enter, [&](std::int32_t a, std::int32_t b, const Node&, const Node&) { return take(a, b); });
  }
  /// self_overlap_pairs() for descend_self() with `enter`: running descend_self() with the
  /// same enter on each pair returned visits what it visits from the root.
  template <typename Enter>
  std::vector<NodePair> self_pairs_below(std::int32_t max_triangles, const Enter& enter) const;

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

  /// The smallest triangle id in a node's subtree (a node index as skip() receives).
  Index node_min_id(std::int32_t node) const { return node_min_ids_[static_cast<size_t>(node)]; }
  /// Per node, the smallest value[t] over the triangles t of its subtree.
  std::vector<double> node_min(const std::vector<double>& value) const;
  /// Per node, the largest value[t] over the triangles t of its subtree.
  std::vector<double> node_max(const std::vector<double>& value) const;

  /// Per node, combine() of leaf(t) over the triangles t of its subtree, from `init`: a leaf
  /// folds its triangles in order, an inner node its two children's values. Children come after
  /// their parent in nodes_, so a reverse pass sees them first.
  template <typename T, typename Leaf, typename Combine>
  std::vector<T> fold_nodes(const T& init, const Leaf& leaf, const Combine& combine) const {
    std::vector<T> out(nodes_.size(), init);
    for (size_t n = nodes_.size(); n-- > 0;) {
      const Node& node = nodes_[n];
      if (node.count > 0) {
        for (std::int32_t k = node.first; k < node.first + node.count; ++k)
          out[n] = combine(out[n], leaf(order_[static_cast<size_t>(k)]));
      } else {
        out[n] = combine(out[static_cast<size_t>(node.first)], out[static_cast<size_t>(node.first) + 1]);
      }
    }
    return out;
  }

  class PairSearch;

 private:
  static constexpr int kLeafSize = 4;
  struct Node {
    AABB box;
    std::int32_t first;  ///< leaf: first index into order_; inner: left child (right = left+1)
    std::int32_t count;  ///< leaf: number of triangles; inner: 0
  };
  /// Nodes of a subtree over n triangles, for every n its ranges split into (n / 2 and the
  /// rest, down to kLeafSize): filled in before a build, read during it.
  struct SubtreeSizes;
  /// A subtree left for later by build_node(): its arguments.
  struct Pending {
    std::int32_t slot, begin, end, next;
  };
  /// A triangle's place in a split: its centroid coordinate along the split axis, as an
  /// integer of the same order, then its id.
  struct SplitKey {
    std::uint64_t key;
    std::uint32_t id;
    /// (key, id) lexicographically, computed without branches.
    friend bool operator<(const SplitKey& a, const SplitKey& b) {
      const int below = a.key < b.key, level = a.key == b.key, id_below = a.id < b.id;
      return (below | (level & id_below)) != 0;
    }
  };
  /// Reorders [first, last) as std::nth_element does (the smallest before `nth`), without
  /// branching on the comparisons.
  static void select_nth(SplitKey* first, SplitKey* nth, SplitKey* last);
  /// What build_node() reads, and the keys it reorders.
  struct BuildInput;
  /// Builds the subtree of triangles order_[begin, end) into node `slot` (a leaf gets its box,
  /// an inner node's comes at the end of build()); its children, if any, go to `next` and
  /// next + 1, their descendants after them in depth-first order. With `pending`, a subtree of
  /// at most `grain` triangles is left to be built later (recorded).
  void build_node(std::int32_t slot, std::int32_t begin, std::int32_t end, std::int32_t next,
                  BuildInput& in, std::vector<Pending>* pending, std::int32_t grain);
  /// Whether a descent of the node pair (na, nb), not two leaves, splits na: the node with
  /// the larger box (the sum of its sides), never a leaf.
  static bool splits_first(const Node& na, const Node& nb) {
    auto size = [](const AABB& box) {
      const Vec3 e = box.hi - box.lo;
      return e.x() + e.y() + e.z();
    };
    return nb.count > 0 || (na.count == 0 && size(na.box) >= size(nb.box));
  }
  /// self_overlaps()'s test of a node pair for descend_self(): overlapping boxes (x != y),
  /// and not skipped.
  template <typename Skip>
  auto overlap_test(const Skip& skip) const {
    return [this, &skip](std::int32_t x, std::int32_t y) {
      return x == y ? !skip(x, x)
                    : boxes_overlap(nodes_[static_cast<size_t>(x)].box, nodes_[static_cast<size_t>(y)].box) && !skip(x, y);
    };
  }
  /// The descent shared by descend_self() and self_pairs_below(): from `start` (on `stack`,
  /// cleared first), passes over a pair unless enter(a, b), and splits it (push_self_split())
  /// unless done(a, b, node a, node b) has taken it whole.
  template <typename Enter, typename Done>
  void walk_self(const NodePair& start, std::vector<NodePair>& stack, const Enter& enter, const Done& done) const;
  /// Pushes the node pairs that self_overlaps() splits the pair (a, b) into (not two leaves
  /// nor one leaf with itself), in the order it takes them (the last pushed first).
  void push_self_split(const NodePair& pair, std::vector<NodePair>& stack) const {
    const auto [a, b] = pair;
    const Node& na = nodes_[static_cast<size_t>(a)];
    const Node& nb = nodes_[static_cast<size_t>(b)];
    if (a == b) {
      stack.push_back({na.first, na.first + 1});
      stack.push_back({na.first + 1, na.first + 1});
      stack.push_back({na.first, na.first});
    } else if (splits_first(na, nb)) {
      stack.push_back({na.first + 1, b});
      stack.push_back({na.first, b});
    } else {
      stack.push_back({a, nb.first + 1});
      stack.push_back({a, nb.first});
    }
  }
  std::vector<Node> nodes_;
  std::vector<Index> order_;
  std::vector<AABB> leaf_boxes_;  ///< boxes in order_ order
  std::vector<Index> node_min_ids_;  ///< per node, the smallest triangle id of its subtree
};

template <typename Bound, typename Visit, typename Skip>
void TriangleBvh::query(const AABB& q, const Bound& bound, const Visit& visit, const Skip& skip) const {
  if (nodes_.empty()) return;
  // Each entry keeps the node's squared distance, computed once when its parent ordered its
  // children, and compared again with the bound (which may have dropped) when it comes up.
  struct Entry {
    std::int32_t node;
    double d2;
  };
  Entry stack[64];
  int top = 0;
  stack[top++] = {0, box_distance_squared(q, nodes_[0].box)};
  while (top > 0) {
    const auto [at, d2] = stack[--top];
    const Node& node = nodes_[static_cast<size_t>(at)];
    double b = bound();
    if (d2 > b * b || skip(at)) continue;
    if (node.count > 0) {
      for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
        const double dt = box_distance_squared(q, leaf_boxes_[static_cast<size_t>(k)]);
        b = bound();
        if (dt <= b * b) visit(order_[static_cast<size_t>(k)], dt);
      }
      continue;
    }
    const std::int32_t l = node.first, r = node.first + 1;
    const double dl = box_distance_squared(q, nodes_[static_cast<size_t>(l)].box);
    const double dr = box_distance_squared(q, nodes_[static_cast<size_t>(r)].box);
    // Push the farther child first so the nearer one is searched first.
    if (dl <= dr) {
      stack[top++] = {r, dr};
      stack[top++] = {l, dl};
    } else {
      stack[top++] = {l, dl};
      stack[top++] = {r, dr};
    }
  }
}

template <typename Skip, typename Visit>
void TriangleBvh::query_overlaps(const AABB& q, const Skip& skip, const Visit& visit, std::int32_t from) const {
  if (nodes_.empty()) return;
  std::int32_t stack[64];
  int top = 0;
  stack[top++] = from;
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

template <typename Skip, typename Visit>
void TriangleBvh::self_overlaps(const NodePair& start, const Skip& skip, const Visit& visit) const {
  descend_self(start, overlap_test(skip), [&](Index t, Index u, const AABB& bt, const AABB& bu) {
    if (boxes_overlap(bt, bu)) visit(t, u);
  });
}

template <typename Enter, typename Done>
void TriangleBvh::walk_self(const NodePair& start, std::vector<NodePair>& stack, const Enter& enter,
                            const Done& done) const {
  stack.clear();
  stack.push_back(start);
  while (!stack.empty()) {
    const auto [a, b] = stack.back();
    stack.pop_back();
    if (!enter(a, b)) continue;
    if (!done(a, b, nodes_[static_cast<size_t>(a)], nodes_[static_cast<size_t>(b)])) push_self_split({a, b}, stack);
  }
}

template <typename Enter, typename Visit>
void TriangleBvh::descend_self(const NodePair& start, const Enter& enter, const Visit& visit) const {
  if (nodes_.empty()) return;
  thread_local std::vector<NodePair> stack;  // reused: called per unit of work
  walk_self(start, stack, enter, [&](std::int32_t a, std::int32_t b, const Node& na, const Node& nb) {
    if (na.count == 0 || (a != b && nb.count == 0)) return false;  // not two leaves: split
    for (std::int32_t k = na.first; k < na.first + na.count; ++k)
      for (std::int32_t m = a == b ? k + 1 : nb.first; m < nb.first + nb.count; ++m)
        visit(order_[static_cast<size_t>(k)], order_[static_cast<size_t>(m)], leaf_boxes_[static_cast<size_t>(k)],
              leaf_boxes_[static_cast<size_t>(m)]);
    return true;
  });
}

template <typename Enter>
std::vector<TriangleBvh::NodePair> TriangleBvh::self_pairs_below(std::int32_t max_triangles, const Enter& enter) const {
  std::vector<NodePair> out;
  if (nodes_.empty()) return out;
  // Triangles per subtree.
  const std::vector<std::int32_t> count =
      fold_nodes(std::int32_t{0}, [](Index) { return std::int32_t{1}; }, [](std::int32_t x, std::int32_t y) { return x + y; });
  // The same expansion as descend_self(), in the same order, stopping at small pairs.
  std::vector<NodePair> stack;
  walk_self({0, 0}, stack, enter, [&](std::int32_t a, std::int32_t b, const Node& na, const Node& nb) {
    const std::int32_t held = a == b ? count[static_cast<size_t>(a)] : count[static_cast<size_t>(a)] + count[static_cast<size_t>(b)];
    if (held > max_triangles && (na.count == 0 || nb.count == 0)) return false;
    out.push_back({a, b});
    return true;
  });
  return out;
}

/// Best-first search of the triangle pairs of pairs of hierarchies (a, b), descending both
/// together: run() expands (pair, node of a, node of b) entries in nondecreasing squared box
/// distance while that distance is within bound(), which is re-read before each step (visit may
/// lower it). An entry splits the node with the larger box (the sum of its sides), never a
/// leaf; two leaves are visited at once: each pair of their triangles whose boxes are within
/// the bound at that moment. So once the bound has come down to an answer d, no pair of leaves
/// farther apart than d is opened and no triangle pair whose boxes are farther apart than d is
/// visited. Pairs of hierarchies may be added between runs: a caller that adds them in
/// nondecreasing order of a lower bound L on their roots' distance and runs up to L before
/// each addition keeps the global order. Equal distances are taken by pair number, then by the
/// smallest triangle id under the node of a (a caller breaking ties on a's ids meets small ids
/// first), then by node; so the search is deterministic. clear() keeps the allocations.
///
/// Descending a's hierarchy too, rather than each triangle of a into b's on its own, shares
/// the upper levels among neighbouring triangles: see docs/algorithms.md, "Inter-object distance".
class TriangleBvh::PairSearch {
 public:
  void clear() {
    pairs_.clear();
    heap_.clear();
  }
  /// Adds the pair (a, b) unless a hierarchy is empty or their roots are farther apart than
  /// `bound`; returns its index either way (pairs are numbered in the order added). Both must
  /// outlive the search.
  std::size_t add(const TriangleBvh& a, const TriangleBvh& b, double bound) {
    return add(a, b, bound, nullptr, nullptr);
  }
  /// The same where distances are also bounded by the projections onto the diagonals: per
  /// hierarchy, those of its nodes and triangles (HierarchyDiagonals). Boxes' squared
  /// distances are raised (raised_distance_squared()), for the order, the bound and the d2
  /// passed to visit alike; the caller's bound must carry a slack above the projections'
  /// rounding (a few 2^-53 of the largest coordinate).
  std::size_t add(const TriangleBvh& a, const TriangleBvh& b, double bound, const HierarchyDiagonals* da,
                  const HierarchyDiagonals* db) {
    const std::size_t p = pairs_.size();
    pairs_.push_back({&a, &b, da && db ? da : nullptr, da && db ? db : nullptr});
    if (!a.nodes_.empty() && !b.nodes_.empty()) {
      const double d2 = node_d2(pairs_.back(), 0, 0);
      if (d2 <= bound * bound) push({d2, static_cast<std::int32_t>(p), 0, 0, a.node_min_ids_[0]});
    }
    return p;
  }
  /// Visits pairs as described above, stopping at the first entry beyond bound() or beyond
  /// `until_d2` (squared). keep_node(pair, node of a) and keep_triangle(pair, triangle of a):
  /// whether that subtree or triangle of a may still be part of a better pair (entries and
  /// triangles for which they are false are dropped); visit(pair, triangle of a, triangle of b,
  /// squared box distance).
  template <typename Bound, typename KeepNode, typename KeepTriangle, typename Visit>
  void run(const Bound& bound, const KeepNode& keep_node, const KeepTriangle& keep_triangle,
           const Visit& visit, double until_d2 = std::numeric_limits<double>::infinity());

 private:
  struct Pair {
    const TriangleBvh* a;
    const TriangleBvh* b;
    const HierarchyDiagonals* da;  ///< both null, or both set
    const HierarchyDiagonals* db;
  };
  static double node_d2(const Pair& p, std::int32_t na, std::int32_t nb) {
    const auto ua = static_cast<std::size_t>(na), ub = static_cast<std::size_t>(nb);
    const double d2 = box_distance_squared(p.a->nodes_[ua].box, p.b->nodes_[ub].box);
    return p.da ? raised_distance_squared(d2, p.da->nodes[ua], p.db->nodes[ub]) : d2;
  }
  struct Entry {
    double d2;
    std::int32_t pair;
    std::int32_t node_a;
    std::int32_t node_b;
    Index rank;  ///< the smallest triangle id under node_a
    bool operator>(const Entry& o) const {
      if (d2 != o.d2) return d2 > o.d2;
      if (pair != o.pair) return pair > o.pair;
      if (rank != o.rank) return rank > o.rank;
      return node_a != o.node_a ? node_a > o.node_a : node_b > o.node_b;
    }
  };
  void push(const Entry& e) {
    heap_.push_back(e);
    std::push_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
  }
  std::vector<Pair> pairs_;
  std::vector<Entry> heap_;
};

template <typename Bound, typename KeepNode, typename KeepTriangle, typename Visit>
void TriangleBvh::PairSearch::run(const Bound& bound, const KeepNode& keep_node,
                                  const KeepTriangle& keep_triangle, const Visit& visit,
                                  double until_d2) {
  while (!heap_.empty()) {
    const double b = bound();
    const Entry e = heap_.front();
    if (e.d2 > b * b || e.d2 > until_d2) return;
    std::pop_heap(heap_.begin(), heap_.end(), std::greater<Entry>());
    heap_.pop_back();
    const auto p = static_cast<std::size_t>(e.pair);
    if (!keep_node(p, e.node_a)) continue;
    const TriangleBvh& ta = *pairs_[p].a;
    const TriangleBvh& tb = *pairs_[p].b;
    const Node& na = ta.nodes_[static_cast<std::size_t>(e.node_a)];
    const Node& nb = tb.nodes_[static_cast<std::size_t>(e.node_b)];
    const Pair& pr = pairs_[p];
    if (na.count > 0 && nb.count > 0) {
      for (std::int32_t i = na.first; i < na.first + na.count; ++i) {
        const Index t = ta.order_[static_cast<std::size_t>(i)];
        if (!keep_triangle(p, t)) continue;
        const AABB& box = ta.leaf_boxes_[static_cast<std::size_t>(i)];
        for (std::int32_t k = nb.first; k < nb.first + nb.count; ++k) {
          const Index u = tb.order_[static_cast<std::size_t>(k)];
          double d2 = box_distance_squared(box, tb.leaf_boxes_[static_cast<std::size_t>(k)]);
          if (pr.da)
            d2 = raised_distance_squared(d2, pr.da->triangles[static_cast<std::size_t>(t)], pr.db->triangles[static_cast<std::size_t>(u)]);
          const double bk = bound();
          if (d2 <= bk * bk) visit(p, t, u, d2);
        }
      }
      continue;
    }
    if (splits_first(na, nb)) {
      for (std::int32_t c = na.first; c < na.first + 2; ++c) {
        const double d2 = node_d2(pr, c, e.node_b);
        if (d2 <= b * b) push({d2, e.pair, c, e.node_b, ta.node_min_ids_[static_cast<std::size_t>(c)]});
      }
    } else {
      for (std::int32_t c = nb.first; c < nb.first + 2; ++c) {
        const double d2 = node_d2(pr, e.node_a, c);
        if (d2 <= b * b) push({d2, e.pair, e.node_a, c, e.rank});
      }
    }
  }
}

}  // namespace vproxq
