// Stage II on the GPU: the 2nd-order discrete Voronoi diagram at the sample voxels (paper 4.3,
// 5.2), one invocation per sample voxel, gathering the triangles of the bins around it.
// Host side and error bound: gl/voronoi_backend.{hpp,cpp}; the CPU twin:
// core/voronoi/cpu_backend.cpp (same algorithm in double).
//
// Storage buffers (std430; coordinates relative to the grid origin):
//   binding 0  triangles      9 floats per triangle: x0 y0 z0 x1 y1 z1 x2 y2 z2
//   binding 1  triangle_info  ivec4 per triangle: site, and the bin coordinates (x, y, z) of the
//                             first bin its bounding box overlaps (to visit it only once)
//   binding 2  bin_offsets    CSR offsets, bin count + 1 ints
//   binding 3  bin_triangles  triangle ids, bin after bin
//   binding 4  samples        uvec4 per sample voxel of this batch: its voxel coordinates
//                             (x, y, z) and its band (float bits)
//   binding 5  results        ivec4 per sample voxel of this batch: site1, site2, and the float
//                             bits of dist1, dist2 (site -1 and dist = band when none); site1
//                             kIncomplete (-2) when the loops did not visit every bin entry:
//                             some drivers cap an invocation's loop iterations (Mesa's llvmpipe
//                             stops every loop after 65535 in all, silently), and the host then
//                             computes that sample another way
//   binding 8  exclude_sites  int per sample voxel of this batch: a site whose triangles are
//                             ignored there (DvdInput::exclude_site), or -1
// Uniforms: sample_count (this batch), cell, dims_x/y/z (grid), bin_size, bin_dims_x/y,
// prefilter_margin (see below).
// Defines: LOCAL_SIZE, the work group size (default 64).
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif

layout(local_size_x = LOCAL_SIZE) in;

layout(std430, binding = 0) readonly buffer Triangles { float triangles[]; };
layout(std430, binding = 1) readonly buffer TriangleInfo { ivec4 triangle_info[]; };
layout(std430, binding = 2) readonly buffer BinOffsets { int bin_offsets[]; };
layout(std430, binding = 3) readonly buffer BinTriangles { int bin_triangles[]; };
layout(std430, binding = 4) readonly buffer Samples { uvec4 samples[]; };
layout(std430, binding = 5) writeonly buffer Results { ivec4 results[]; };
layout(std430, binding = 8) readonly buffer ExcludeSites { int exclude_sites[]; };

uniform uint sample_count;
uniform float cell;
uniform int dims_x;
uniform int dims_y;
uniform int dims_z;
uniform int bin_size;
uniform int bin_dims_x;
uniform int bin_dims_y;
// A triangle is skipped when the distance to its bounding box exceeds the current cut-off
// (band, or the 2nd site's distance so far) by more than this: twice the error bound, which
// covers the error of the box distance and of the triangle distance, so a skipped triangle's
// computed distance would have been above the cut-off and could not have changed the result.
uniform float prefilter_margin;

const int kNoSite = 0x7FFFFFFF;  // larger than every site: "smaller id first" needs no case
const int kNoIndex = -1;
const int kIncomplete = -2;
// Squared lengths at or below 2^-100 count as zero: the division they would feed is then
// inside GLSL's accuracy range [2^-126, 2^126], and treating such an edge or height as zero
// moves the result by at most 2^-50 (the absolute term of the error bound).
const float kMinSquared = 7.8886090522101181e-31;  // 2^-100
// Relative widening of the bin search box, in cell units: covers the float rounding of the
// box bounds (a few 2^-23) with a wide margin, so every bin holding a triangle within the band
// (as binned on the host, in double) is visited.
const float kBinSearchSlack = 3.814697265625e-06;  // 2^-18

// Squared distance from p to the segment [a, a + e], from w = p - a, e and ee = dot(e, e).
// A segment with ee <= kMinSquared is its point a.
float segment_distance_squared(vec3 w, vec3 e, float ee) {
  precise float t = ee > kMinSquared ? clamp(dot(w, e) / ee, 0.0, 1.0) : 0.0;
  precise vec3 v = w - t * e;
  precise float d2 = dot(v, v);
  return d2;
}

// Squared distance from p to the closed triangle (c0, c1, c2), any shape. The minimum of:
//  - the three edge distances (always: they also cover degenerate triangles), and
//  - a face candidate, in the frame of the longest edge ab: h is the part of ac orthogonal to
//    ab (Gram-Schmidt, two passes), p's foot is a + t ab + lambda h, and it is used only when its
//    barycentric coordinates (1 - t - lambda (1 - tau), t - lambda tau, lambda) are >= 0.
//    Unlike a cross-product normal this frame stays accurate for slivers and caps: the error
//    of h only tilts the triangle by a few ulps of its longest edge (see voronoi_backend.cpp
//    for the error analysis).
// Every candidate is the distance to a point of the triangle up to rounding, so none is too
// small; the edges or the face candidate are close to the true distance.
float point_triangle_distance_squared(vec3 p, vec3 c0, vec3 c1, vec3 c2) {
  precise vec3 w0 = p - c0;
  precise vec3 w1 = p - c1;
  precise vec3 w2 = p - c2;
  precise vec3 e0 = c1 - c0;
  precise vec3 e1 = c2 - c1;
  precise vec3 e2 = c0 - c2;
  precise float l0 = dot(e0, e0);
  precise float l1 = dot(e1, e1);
  precise float l2 = dot(e2, e2);
  precise float best = min(min(segment_distance_squared(w0, e0, l0),
                               segment_distance_squared(w1, e1, l1)),
                           segment_distance_squared(w2, e2, l2));
  // Longest edge k joins a = c_k and b = c_{k+1}; c = c_{k+2}, so ac = -e_{k+2}.
  vec3 ap = w0;
  vec3 ab = e0;
  vec3 ac = -e2;
  float ll = l0;
  if (l1 > ll && l1 >= l2) {
    ap = w1;
    ab = e1;
    ac = -e0;
    ll = l1;
  } else if (l2 > ll) {
    ap = w2;
    ab = e2;
    ac = -e1;
    ll = l2;
  }
  if (ll > kMinSquared) {
    precise float tau = dot(ac, ab) / ll;
    precise vec3 h1 = ac - tau * ab;
    precise float mu = dot(h1, ab) / ll;
    precise vec3 h = h1 - mu * ab;
    precise float tau2 = tau + mu;
    precise float hh = dot(h, h);
    if (hh > kMinSquared) {
      precise float t = dot(ap, ab) / ll;
      precise float lambda = dot(ap, h) / hh;
      precise float beta_b = t - lambda * tau2;
      precise float beta_a = (1.0 - t) - lambda * (1.0 - tau2);
      if (lambda >= 0.0 && beta_b >= 0.0 && beta_a >= 0.0) {
        precise vec3 v = (ap - t * ab) - lambda * h;
        precise float face = dot(v, v);
        best = min(best, face);
      }
    }
  }
  return best;
}

// (d, s) comes before (d_other, s_other): smaller distance, ties to the smaller site.
bool before(float d, int s, float d_other, int s_other) {
  return d < d_other || (d == d_other && s < s_other);
}

vec3 corner(int t, int k) {
  int i = 9 * t + 3 * k;
  return vec3(triangles[i], triangles[i + 1], triangles[i + 2]);
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= sample_count) {
    return;
  }
  float band = uintBitsToFloat(samples[i].w);
  int skip = exclude_sites[i];
  // With an excluded site only the nearest other site is asked for (DvdOutput).
  bool nearest_only = skip != kNoIndex;
  ivec3 voxel = ivec3(samples[i].xyz);
  vec3 centre = vec3(voxel) + 0.5;  // in cell units, exact
  vec3 q = centre * cell;

  // Bins overlapping the box centre -+ band (in cells), widened, clamped to the grid.
  ivec3 last_voxel = ivec3(dims_x, dims_y, dims_z) - 1;
  float reach = min(band / cell, float(max(dims_x, max(dims_y, dims_z))) + 1.0);
  vec3 widen = (centre + reach + 1.0) * kBinSearchSlack;
  ivec3 bin_lo = min(ivec3(max(floor(centre - reach - widen), vec3(0.0))), last_voxel) / bin_size;
  ivec3 bin_hi = min(ivec3(floor(centre + reach + widen)), last_voxel) / bin_size;

  // The two nearest distinct sites, as squared distances.
  float d1 = uintBitsToFloat(0x7F800000u);  // +infinity
  float d2 = d1;
  int s1 = kNoSite;
  int s2 = kNoSite;
  float cutoff = band + prefilter_margin;
  float cutoff_squared = cutoff * cutoff;
  // What the loops must visit, and what they did (see kIncomplete).
  uint bins_planned = uint(bin_hi.x - bin_lo.x + 1) * uint(bin_hi.y - bin_lo.y + 1) * uint(bin_hi.z - bin_lo.z + 1);
  uint bins_visited = 0u;
  int entries_planned = 0;
  int entries_visited = 0;
  for (int bz = bin_lo.z; bz <= bin_hi.z; ++bz) {
    for (int by = bin_lo.y; by <= bin_hi.y; ++by) {
      for (int bx = bin_lo.x; bx <= bin_hi.x; ++bx) {
        ivec3 here = ivec3(bx, by, bz);
        int b = bx + bin_dims_x * (by + bin_dims_y * bz);
        int end = bin_offsets[b + 1];
        ++bins_visited;
        entries_planned += end - bin_offsets[b];
        for (int j = bin_offsets[b]; j < end; ++j) {
          ++entries_visited;
          int t = bin_triangles[j];
          ivec4 info = triangle_info[t];
          // Visit a triangle once: in the first visited bin of its own range.
          if (max(info.yzw, bin_lo) != here || info.x == skip) {
            continue;
          }
          vec3 a = corner(t, 0);
          vec3 b3 = corner(t, 1);
          vec3 c = corner(t, 2);
          vec3 gap = max(max(min(min(a, b3), c) - q, q - max(max(a, b3), c)), vec3(0.0));
          if (dot(gap, gap) > cutoff_squared) {
            continue;
          }
          float d = point_triangle_distance_squared(q, a, b3, c);
          int s = info.x;
          float previous_limit = nearest_only ? d1 : d2;
          if (s == s1) {
            d1 = min(d1, d);
          } else if (before(d, s, d1, s1)) {
            d2 = d1;  // also right when s == s2: its old, larger value is dropped
            s2 = s1;
            d1 = d;
            s1 = s;
          } else if (s == s2) {
            d2 = min(d2, d);
          } else if (before(d, s, d2, s2)) {
            d2 = d;
            s2 = s;
          }
          float limit = nearest_only ? d1 : d2;
          if (limit != previous_limit) {
            cutoff = min(band, sqrt(limit)) + prefilter_margin;
            cutoff_squared = cutoff * cutoff;
          }
        }
      }
    }
  }
  float dist1 = sqrt(d1);
  float dist2 = sqrt(d2);
  bool has1 = s1 != kNoSite && dist1 < band;
  bool has2 = !nearest_only && s2 != kNoSite && dist2 < band;
  bool complete = bins_visited == bins_planned && entries_visited == entries_planned;
  results[i] = ivec4(complete ? (has1 ? s1 : kNoIndex) : kIncomplete, has2 ? s2 : kNoIndex,
                     floatBitsToInt(has1 ? dist1 : band), floatBitsToInt(has2 ? dist2 : band));
}
