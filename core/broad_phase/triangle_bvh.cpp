#include "core/broad_phase/triangle_bvh.hpp"

#include "core/parallel.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>

namespace vproxq {

struct TriangleBvh::SubtreeSizes {
  /// (n, nodes of a subtree over n triangles): each depth holds ranges of at most two sizes
  /// (n / 2^d rounded down or up), so there are few.
  std::vector<std::pair<std::int32_t, std::int32_t>> nodes;

  explicit SubtreeSizes(std::int32_t n) { count(n); }
  std::int32_t of(std::int32_t n) const {
    for (const auto& [size, c] : nodes)
      if (size == n) return c;
    return 0;  // not reached: every size of the build was counted
  }

 private:
  std::int32_t count(std::int32_t n) {
    for (const auto& [size, c] : nodes)
      if (size == n) return c;
    const std::int32_t c = n <= kLeafSize ? 1 : 1 + count(n / 2) + count(n - n / 2);
    nodes.emplace_back(n, c);
    return c;
  }
};

namespace {

/// An unsigned integer whose order is that of the double `x` (not NaN), with -0 and +0 equal.
inline std::uint64_t ordered_bits(double x) {
  const double y = x + 0.0;  // -0 + 0 = +0
  std::uint64_t u;
  std::memcpy(&u, &y, sizeof u);
  return (u >> 63) != 0 ? ~u : u | (std::uint64_t{1} << 63);
}

}  // namespace

/// The same halves as std::nth_element (a strict order makes them unique). The partitions move
/// every record and advance their boundary by each comparison's result, with no branch on it:
/// the splits' comparisons are unpredictable, and std::nth_element (on ids, reading centroids
/// through them) took most of a build's time. Builds of the 400 blobs of blobs-200's first two
/// frames (180 triangles each) took 9.4 ms before, 5.6 after; of funnel-227 (18,484), 4.3 and
/// 2.7 (one thread, fastest of 30).
void TriangleBvh::select_nth(SplitKey* first, SplitKey* nth, SplitKey* last) {
  // A median of three can be fooled round after round by some orders: past twice the rounds
  // that halving would take, std::nth_element (introselect) finishes the range, with the same
  // halves.
  int rounds = 16;
  for (std::ptrdiff_t n = last - first; n > 1; n /= 2) rounds += 2;
  while (last - first > 8) {
    if (--rounds < 0) {
      std::nth_element(first, nth, last);
      return;
    }
    // Median of three as the pivot, at last - 1.
    SplitKey* mid = first + (last - first) / 2;
    SplitKey* back = last - 1;
    if (*mid < *first) std::swap(*mid, *first);
    if (*back < *mid) {
      std::swap(*back, *mid);
      if (*mid < *first) std::swap(*mid, *first);
    }
    std::swap(*mid, *back);
    const SplitKey pivot = *back;
    SplitKey* store = first;
    for (SplitKey* it = first; it < back; ++it) {
      const SplitKey x = *it;
      const bool smaller = x < pivot;
      *it = *store;
      *store = x;
      store += smaller;
    }
    std::swap(*store, *back);  // the pivot between the halves
    if (store == nth) return;
    if (nth < store) {
      last = store;
    } else {
      first = store + 1;
    }
  }
  for (SplitKey* it = first + 1; it < last; ++it) {  // insertion sort of the few left
    const SplitKey x = *it;
    SplitKey* j = it;
    for (; j > first && x < *(j - 1); --j) *j = *(j - 1);
    *j = x;
  }
}

struct TriangleBvh::BuildInput {
  const std::vector<AABB>& boxes;
  std::vector<Vec3> centroids;  ///< of the boxes
  std::vector<SplitKey> keys;   ///< scratch, by position in order_
  SubtreeSizes sizes;
};

void TriangleBvh::build(const std::vector<AABB>& boxes, int threads) {
  nodes_.clear();
  node_min_ids_.clear();
  order_.resize(boxes.size());
  std::iota(order_.begin(), order_.end(), 0);
  leaf_boxes_.clear();
  if (boxes.empty()) return;
  const auto n = static_cast<std::int32_t>(boxes.size());
  BuildInput in{boxes, std::vector<Vec3>(boxes.size()), std::vector<SplitKey>(boxes.size()), SubtreeSizes(n)};
  for (size_t t = 0; t < boxes.size(); ++t) in.centroids[t] = boxes[t].center();
  nodes_.assign(static_cast<size_t>(in.sizes.of(n)), Node{});
  if (threads <= 1) {
    build_node(0, 0, n, 1, in, nullptr, 0);
  } else {
    // The top levels here, down to subtrees of at most n / (2 threads) triangles; those in
    // parallel (disjoint ranges of order_, of the keys and of nodes_).
    std::vector<Pending> pending;
    build_node(0, 0, n, 1, in, &pending, std::max<std::int32_t>(kLeafSize, n / (2 * threads)));
    parallel_for(pending.size(), threads, [&](size_t k) {
      const Pending& p = pending[k];
      build_node(p.slot, p.begin, p.end, p.next, in, nullptr, 0);
    });
  }
  // Leaves have their boxes; an inner node's is the union of its children's (min and max are
  // exact: the box of its triangles). Children come after their parent.
  for (size_t k = nodes_.size(); k-- > 0;) {
    Node& node = nodes_[k];
    if (node.count > 0) continue;
    node.box = nodes_[static_cast<size_t>(node.first)].box;
    node.box.extend(nodes_[static_cast<size_t>(node.first) + 1].box);
  }
  leaf_boxes_.resize(order_.size());
  for (size_t k = 0; k < order_.size(); ++k) leaf_boxes_[k] = boxes[static_cast<size_t>(order_[k])];
  node_min_ids_ = fold_nodes(std::numeric_limits<Index>::max(), [](Index t) { return t; },
                             [](Index x, Index y) { return std::min(x, y); });
}

std::vector<double> TriangleBvh::node_min(const std::vector<double>& value) const {
  return fold_nodes(std::numeric_limits<double>::infinity(), [&](Index t) { return value[static_cast<size_t>(t)]; },
                    [](double x, double y) { return std::min(x, y); });
}

std::vector<double> TriangleBvh::node_max(const std::vector<double>& value) const {
  return fold_nodes(-std::numeric_limits<double>::infinity(), [&](Index t) { return value[static_cast<size_t>(t)]; },
                    [](double x, double y) { return std::max(x, y); });
}

std::vector<AABB> TriangleBvh::node_unions(const std::vector<AABB>& boxes) const {
  return fold_nodes(AABB{}, [&](Index t) { return boxes[static_cast<size_t>(t)]; }, [](AABB x, const AABB& y) {
    x.extend(y);
    return x;
  });
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
void TriangleBvh::build_node(std::int32_t slot, std::int32_t begin, std::int32_t end, std::int32_t next,
                             BuildInput& in, std::vector<Pending>* pending, std::int32_t grain) {
  if (pending && end - begin <= grain) {
    pending->push_back({slot, begin, end, next});
    return;
  }
  Node node;
  if (end - begin <= kLeafSize) {
    for (std::int32_t k = begin; k < end; ++k) node.box.extend(in.boxes[static_cast<size_t>(order_[static_cast<size_t>(k)])]);
    node.first = begin;
    node.count = end - begin;
    nodes_[static_cast<size_t>(slot)] = node;
    return;
  }
  AABB cb;
  for (std::int32_t k = begin; k < end; ++k) cb.extend(in.centroids[static_cast<size_t>(order_[static_cast<size_t>(k)])]);
  int axis = 0;
  const Vec3 ext = cb.hi - cb.lo;
  if (ext.y() > ext[axis]) axis = 1;
  if (ext.z() > ext[axis]) axis = 2;
  // The median along the axis, by centroid coordinate, then id.
  SplitKey* keys = in.keys.data();
  for (std::int32_t k = begin; k < end; ++k) {
    const Index t = order_[static_cast<size_t>(k)];
    keys[k] = {ordered_bits(in.centroids[static_cast<size_t>(t)][axis]), static_cast<std::uint32_t>(t)};
  }
  const std::int32_t mid = begin + (end - begin) / 2;
  select_nth(keys + begin, keys + mid, keys + end);
  for (std::int32_t k = begin; k < end; ++k) order_[static_cast<size_t>(k)] = static_cast<Index>(keys[k].id);
  // Children are an adjacent pair; the left subtree's descendants follow them, then the right's
  // (the depth-first order in which a serial build allocated them). The box comes at the end
  // of build(), from the children's.
  node.first = next;
  node.count = 0;
  nodes_[static_cast<size_t>(slot)] = node;
  build_node(next, begin, mid, next + 2, in, pending, grain);
  build_node(next + 1, mid, end, next + 2 + in.sizes.of(mid - begin) - 1, in, pending, grain);
}

}  // namespace vproxq
