#pragma once
// A stable sort by an unsigned integer key (LSD radix sort, 11 bits per pass), for Stage II's
// voxel lists: hundreds of thousands of samples per frame keyed by voxel id, which
// std::sort took 15-20 ms to order on the 200-object scene.
#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

namespace vproxq {

/// Sorts `items` by key(item) (a std::uint64_t), keeping the order of items with equal keys.
/// Time: one pass to find the largest key, then one pass per 11 bits of it.
template <typename T, typename Key>
void stable_radix_sort(std::vector<T>& items, const Key& key) {
  constexpr int kBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  if (items.size() < 2) return;
  std::uint64_t max_key = 0;
  for (const T& x : items) max_key = std::max<std::uint64_t>(max_key, key(x));
  std::vector<T> scratch(items.size());
  for (int shift = 0; shift < 64 && (max_key >> shift) != 0; shift += kBits) {
    std::array<std::size_t, kBuckets> start{};
    for (const T& x : items) ++start[(key(x) >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& s : start) sum += std::exchange(s, sum);
    for (T& x : items) scratch[start[(key(x) >> shift) & (kBuckets - 1)]++] = std::move(x);
    items.swap(scratch);
  }
}

}  // namespace vproxq
