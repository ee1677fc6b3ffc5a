#pragma once
// Stage I's sorted intervals along one axis (paper 5.1, after Cohen et al. 1995), with the
// search for the interval that overlaps a given one the most in O(log n) rather than by a
// scan of every other object (a scan per object made Stage I quadratic in the number of
// objects: 3.7 s per frame for 20,000 objects).
#include "core/broad_phase/aabb.hpp"
#include "core/types.hpp"

#include <cstddef>
#include <vector>

namespace vproxq {

/// Maxima of a sequence as a segment tree: range maxima and first-match searches in O(log n).
class MaxTree {
 public:
  MaxTree() = default;
  explicit MaxTree(const std::vector<double>& values);

  /// The value at position q.
  double at(std::size_t q) const { return node_[size_ + q]; }

  /// Largest value at positions [l, r); -inf when the range is empty.
  double max(std::size_t l, std::size_t r) const;

  /// First position in [l, r) whose value satisfies `pred`, or r when none does. `pred` must
  /// be monotone (true for a value implies true for every larger one), so that a subtree holds
  /// such a position exactly when its maximum satisfies it.
  template <typename Pred>
  std::size_t first(std::size_t l, std::size_t r, const Pred& pred) const {
    const std::size_t q = first_in(1, 0, size_, l, r, pred);
    return q < r ? q : r;
  }

 private:
  template <typename Pred>
  std::size_t first_in(std::size_t v, std::size_t vl, std::size_t vr, std::size_t l, std::size_t r,
                       const Pred& pred) const {
    if (vr <= l || r <= vl || !pred(node_[v])) return r;
    if (vr - vl == 1) return vl;
    const std::size_t mid = (vl + vr) / 2;
    const std::size_t q = first_in(2 * v, vl, mid, l, r, pred);
    return q < r ? q : first_in(2 * v + 1, mid, vr, l, r, pred);
  }

  std::size_t size_ = 1;      ///< leaves (a power of two)
  std::vector<double> node_;  ///< node v has children 2v, 2v+1; leaves from size_
};

/// The boxes' intervals along axis k, sorted by their low end (ties by object id).
class SortedAxis {
 public:
  /// `objects`: the ids to sort (ids index `boxes`; their boxes must not be empty).
  SortedAxis(const std::vector<Index>& objects, const std::vector<AABB>& boxes, int k);

  /// The object other than `i` whose interval overlaps i's the most, by interval_overlap()
  /// (the nearest interval when none overlaps; the first in sorted order on a tie): exactly
  /// what a scan of every other object in sorted order keeping strict improvements finds.
  /// kNoIndex when i is the only object.
  Index most_overlapping(Index i) const;

 private:
  std::vector<Index> order_;
  std::vector<double> lo_;             ///< low ends, in sorted order
  std::vector<std::size_t> position_;  ///< [object id] -> index into order_
  MaxTree hi_;                         ///< high ends, in sorted order, with range maxima
};

}  // namespace vproxq
