#include "core/voronoi/grid_setup.hpp"

#include "core/parallel.hpp"
#include "core/voronoi/bins.hpp"

#include <algorithm>

namespace vproxq {

namespace {

// Writes triangle t of object i as input triangle g.
void put_triangle(DvdInput& in, const Frame& frame, const StageGrid& sg, size_t i, Index t, size_t g) {
  const Triangle tri = frame.objects[i].triangle(t);
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) {
      const double v = sg.backend_coord(tri[static_cast<size_t>(c)][k], k);
      in.tri_xyz_d[g * 9 + static_cast<size_t>(c * 3 + k)] = v;
      in.tri_xyz[g * 9 + static_cast<size_t>(c * 3 + k)] = static_cast<float>(v);
    }
  in.tri_site[g] = static_cast<std::int32_t>(i);
}

}  // namespace

double median_triangle_side(const FrameBoxes& boxes, const std::function<bool(size_t)>& include) {
  std::vector<double> sides;
  size_t count = 0;
  for (size_t i = 0; i < boxes.triangles.size(); ++i)
    if (include(i)) count += boxes.triangles[i].size();
  sides.reserve(count);
  for (size_t i = 0; i < boxes.triangles.size(); ++i) {
    if (!include(i)) continue;
    for (const AABB& b : boxes.triangles[i]) sides.push_back((b.hi - b.lo).maxCoeff());
  }
  if (sides.empty()) return 0;
  const auto mid = sides.begin() + static_cast<std::ptrdiff_t>(sides.size() / 2);
  std::nth_element(sides.begin(), mid, sides.end());
  return *mid;
}

void fill_dvd_triangles(DvdInput& in, const Frame& frame, const StageGrid& sg,
                        const std::vector<std::vector<Index>>& kept) {
  size_t g = 0;
  for (const auto& k : kept) g += k.size();
  in.tri_xyz.resize(g * 9);
  in.tri_xyz_d.resize(g * 9);
  in.tri_site.resize(g);
  g = 0;
  for (size_t i = 0; i < kept.size(); ++i)
    for (const Index t : kept[i]) put_triangle(in, frame, sg, i, t, g++);
}

std::vector<std::vector<Index>> reachable_triangles(const DvdInput& in, const StageGrid& sg,
                                                    const FrameBoxes& boxes, int threads,
                                                    const std::function<bool(size_t)>& wanted,
                                                    const std::function<bool(size_t, Index)>& also) {
  const std::vector<std::uint8_t> reached = reached_bins(in);
  auto bins_of = [&](const AABB& b) {
    Vec3 lo, hi;
    for (int k = 0; k < 3; ++k) {
      lo[k] = sg.backend_coord(b.lo[k], k);
      hi[k] = sg.backend_coord(b.hi[k], k);
    }
    return bins_overlapping(in, lo, hi);
  };
  std::vector<std::vector<Index>> kept(boxes.triangles.size());
  parallel_for(kept.size(), threads, [&](size_t i) {
    if (boxes.objects[i].empty() || !wanted(i)) return;
    const bool any = reaches(in, reached, bins_of(boxes.objects[i]));
    const auto& tb = boxes.triangles[i];
    for (size_t t = 0; t < tb.size(); ++t)
      if ((any && reaches(in, reached, bins_of(tb[t]))) || also(i, static_cast<Index>(t))) kept[i].push_back(static_cast<Index>(t));
  });
  return kept;
}

}  // namespace vproxq
