#include "core/broad_phase/sorted_axis.hpp"

#include <algorithm>

namespace vproxq {

MaxTree::MaxTree(const std::vector<double>& values) {
  while (size_ < values.size()) size_ *= 2;
  node_.assign(2 * size_, -kInfinity);
  std::copy(values.begin(), values.end(), node_.begin() + static_cast<std::ptrdiff_t>(size_));
  for (std::size_t v = size_ - 1; v >= 1; --v) node_[v] = std::max(node_[2 * v], node_[2 * v + 1]);
}

double MaxTree::max(std::size_t l, std::size_t r) const {
  double m = -kInfinity;
  for (l += size_, r += size_; l < r; l /= 2, r /= 2) {
    if (l & 1) m = std::max(m, node_[l++]);
    if (r & 1) m = std::max(m, node_[--r]);
  }
  return m;
}

SortedAxis::SortedAxis(const std::vector<Index>& objects, const std::vector<AABB>& boxes, int k)
    : order_(objects) {
  std::sort(order_.begin(), order_.end(), [&](Index a, Index b) {
    const double la = boxes[static_cast<std::size_t>(a)].lo[k];
    const double lb = boxes[static_cast<std::size_t>(b)].lo[k];
    return la < lb || (la == lb && a < b);
  });
  lo_.reserve(order_.size());
  std::vector<double> hi;
  hi.reserve(order_.size());
  position_.assign(boxes.size(), 0);
  for (std::size_t q = 0; q < order_.size(); ++q) {
    const AABB& b = boxes[static_cast<std::size_t>(order_[q])];
    lo_.push_back(b.lo[k]);
    hi.push_back(b.hi[k]);
    position_[static_cast<std::size_t>(order_[q])] = q;
  }
  hi_ = MaxTree(hi);
}

// For an interval starting at or before i's (lo <= a_lo), the overlap is min(a_hi, hi) - a_lo:
// monotone in hi, so the best of those is found from the maxima of hi. For one starting after
// (lo > a_lo) it is min(a_hi, hi) - lo <= a_hi - lo, which falls as lo grows: the scan to the
// right stops once a_hi - lo is below the best overlap so far. Both orders hold for the
// computed (rounded) values too, since rounding is monotone, so the choice, ties included, is
// the full scan's.
Index SortedAxis::most_overlapping(Index i) const {
  const std::size_t self = position_[static_cast<std::size_t>(i)];
  const double a_lo = lo_[self], a_hi = hi_.at(self);
  const std::size_t m = order_.size();
  const std::size_t left_end =
      static_cast<std::size_t>(std::upper_bound(lo_.begin(), lo_.end(), a_lo) - lo_.begin());
  double best = -kInfinity;
  std::size_t best_q = m;
  const double h = std::max(hi_.max(0, self), hi_.max(self + 1, left_end));
  if (h > -kInfinity) {  // some other interval starts at or before a_lo
    best = std::min(a_hi, h) - a_lo;
    const auto reaches = [&](double x) { return std::min(a_hi, x) - a_lo >= best; };
    best_q = hi_.first(0, self, reaches);
    if (best_q == self) best_q = hi_.first(self + 1, left_end, reaches);
  }
  for (std::size_t q = left_end; q < m && !(a_hi - lo_[q] < best); ++q) {
    const double ov = std::min(a_hi, hi_.at(q)) - lo_[q];
    if (ov > best) {
      best = ov;
      best_q = q;
    }
  }
  return best_q < m ? order_[best_q] : kNoIndex;
}

}  // namespace vproxq
