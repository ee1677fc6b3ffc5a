// Stage II on the GPU: the 2nd-order discrete Voronoi diagram at the sample voxels (paper 4.3,
// 5.2), one invocation per sample voxel, gathering the triangles of the bins around it.
// Host side and error bound: gl/voronoi_backend.{hpp,cpp}; the CPU twin:
// core/voronoi/cpu_backend.cpp (same algorithm in double).
//
// Storage buffers (std430; coordinates relative to the grid origin):
//   binding 0  triangles      9 floats per triangle: x0 y0 z0 x1 y1 z1 x2 y2 z2
//   binding 1  triangle_info  2 ivec4 per triangle: [2t] site and the bin coordinates (x, y, z)
//                             of the first bin its bounding box overlaps, [2t + 1] 0 and those
//                             of the last (to visit it only once: visit_here())
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
//   binding 8  exclude_sites  ivec4 per sample voxel of this batch: a site whose triangles are
//                             ignored there (DvdInput::exclude_site), or -1; the ids [y, z) of
//                             its triangles when they are consecutive (triangles listed in
//                             site order), else y = z (bin_run()); and 0
// Uniforms: sample_count (this batch), cell, dims_x/y/z (grid), bin_size, bin_dims_x/y/z,
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
layout(std430, binding = 8) readonly buffer ExcludeSites { ivec4 exclude_sites[]; };

uniform uint sample_count;
uniform float cell;
uniform int dims_x;
uniform int dims_y;
uniform int dims_z;
uniform int bin_size;
uniform int bin_dims_x;
uniform int bin_dims_y;
uniform int bin_dims_z;
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

// Distance along one axis from coordinate x to bin b of n (bins `width` wide; the first and the
// last bin reach to -infinity and +infinity: bin coordinates are clamped to the grid).
float bin_axis_gap(float x, int b, int n, float width) {
  float below = b > 0 ? float(b) * width - x : 0.0;
  float above = b + 1 < n ? x - float(b + 1) * width : 0.0;
  return max(max(below, above), 0.0);
}

// The entries of a bin's list [from, to) (ascending triangle ids) holding the ids [lo, hi), as
// [run.x, run.y): a binary search instead of stepping over the entries one by one (a site's
// triangles are consecutive ids: they are one run per bin). run.z is 1 when the positions are
// not what they should be (a search the driver's loop cap cut short: dvd2_gather's kIncomplete).
int first_not_below(int from, int to, int t) {
  int lo = from;
  int hi = to;
  while (lo < hi) {
    int mid = (lo + hi) / 2;
    if (bin_triangles[mid] < t) {
      lo = mid + 1;
    } else {
      hi = mid;
    }
  }
  return lo;
}

bool is_first_not_below(int from, int to, int t, int p) {
  return from <= p && p <= to && (p == from || bin_triangles[p - 1] < t) && (p == to || bin_triangles[p] >= t);
}

ivec3 bin_run(int from, int to, int lo, int hi) {
  // No search where the bin holds none of the ids, or only them (the common cases).
  if (from == to || bin_triangles[from] >= hi || bin_triangles[to - 1] < lo) {
    return ivec3(from, from, 0);
  }
  if (bin_triangles[from] >= lo && bin_triangles[to - 1] < hi) {
    return ivec3(from, to, 0);
  }
  int p0 = first_not_below(from, to, lo);
  int p1 = first_not_below(p0, to, hi);
  bool ok = is_first_not_below(from, to, lo, p0) && is_first_not_below(p0, to, hi, p1);
  return ivec3(p0, p1, ok ? 0 : 1);
}

// Whether triangle t, listed in bin `here`, whose range of bins starts at `first`, is visited
// there: `here` is the bin of its range nearest to `home` (per axis, home's coordinate clamped
// to the range).
bool visit_here(int t, ivec3 first, ivec3 here, ivec3 home) {
  return clamp(home, first, triangle_info[2 * t + 1].yzw) == here;
}

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

// Takes triangle t of site s into the two nearest distinct sites (d1, s1), (d2, s2) of q
// (squared distances), unless its bounding box lies beyond the cut-off; shrinks the cut-off
// when the distance it depends on (d1 with nearest_only, else d2) shrinks.
void consider(int t, int s, vec3 q, float band, bool nearest_only, inout float d1, inout float d2,
              inout int s1, inout int s2, inout float cutoff, inout float cutoff_squared) {
  vec3 a = corner(t, 0);
  vec3 b = corner(t, 1);
  vec3 c = corner(t, 2);
  vec3 gap = max(max(min(min(a, b), c) - q, q - max(max(a, b), c)), vec3(0.0));
  if (dot(gap, gap) > cutoff_squared) {
    return;
  }
  float d = point_triangle_distance_squared(q, a, b, c);
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

// Visits the entries of bin `here` for the sample at q: the excluded site's run
// of entries is passed over (bin_run()), and each other triangle is taken in (consider()) when
// this is the bin visit_here() picks for it. Counts what it plans and visits (kIncomplete).
void scan_bin(ivec3 here, ivec3 home, vec3 q, float band, ivec4 exclude, bool nearest_only,
              inout float d1, inout float d2, inout int s1, inout int s2, inout float cutoff,
              inout float cutoff_squared, inout int entries_planned, inout int entries_visited,
              inout bool searches_ok) {
  int b = here.x + bin_dims_x * (here.y + bin_dims_y * here.z);
  int begin = bin_offsets[b];
  int end = bin_offsets[b + 1];
  // Entries [begin, run.x) and [run.y, end) are visited.
  ivec3 run = ivec3(end, end, 0);
  if (exclude.y < exclude.z) {
    run = bin_run(begin, end, exclude.y, exclude.z);
    searches_ok = searches_ok && run.z == 0;
  }
  entries_planned += (run.x - begin) + (end - run.y);
  for (int j = begin; j < end; ++j) {
    if (j == run.x && run.x < run.y) {
      j = run.y - 1;
      continue;
    }
    ++entries_visited;
    int t = bin_triangles[j];
    ivec4 info = triangle_info[2 * t];
    if (info.x != exclude.x && visit_here(t, info.yzw, here, home)) {
      consider(t, info.x, q, band, nearest_only, d1, d2, s1, s2, cutoff, cutoff_squared);
    }
  }
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= sample_count) {
    return;
  }
  float band = uintBitsToFloat(samples[i].w);
  ivec4 exclude = exclude_sites[i];
  int skip = exclude.x;
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

  // The walk: first the sample's own bin `home` (what it finds shortens the cut-off for the
  // others), then the bins of [bin_lo, bin_hi] in (z, y, x) order but home. A bin farther from
  // q than the cut-off is passed over, and a triangle listed in several bins is visited in one
  // only, the bin of its range nearest to home (visit_here()), which is also the bin of its
  // range nearest to q. So every triangle having a point within the cut-off of q is visited,
  // once: that point lies in a bin of its range, no nearer to q than the one visit_here()
  // picks, which is therefore not passed over. The bins' bounds float(b) * width and q are off
  // by a few float ulps (2^-23) of the coordinates' magnitude, at most about dims + 2 bin_size
  // cells; bin_slack (kBinSearchSlack, 2^-18 of that) covers it, as it covers the host's
  // binning in double.
  ivec3 home = voxel / bin_size;
  float width = cell * float(bin_size);
  float bin_slack = kBinSearchSlack * cell * float(max(dims_x, max(dims_y, dims_z)) + 2 * bin_size);
  // What the loops must visit, and what they did (see kIncomplete).
  ivec3 span = bin_hi - bin_lo + 1;
  int bins_planned = span.x * span.y * span.z + 1;
  int bins_visited = 0;
  int entries_planned = 0;
  int entries_visited = 0;
  bool searches_ok = true;
  scan_bin(home, home, q, band, exclude, nearest_only, d1, d2, s1, s2, cutoff, cutoff_squared,
           entries_planned, entries_visited, searches_ok);
  ++bins_visited;
  for (int bz = bin_lo.z; bz <= bin_hi.z; ++bz) {
    float gz = bin_axis_gap(q.z, bz, bin_dims_z, width);
    for (int by = bin_lo.y; by <= bin_hi.y; ++by) {
      float gy = bin_axis_gap(q.y, by, bin_dims_y, width);
      for (int bx = bin_lo.x; bx <= bin_hi.x; ++bx) {
        ivec3 here = ivec3(bx, by, bz);
        ++bins_visited;
        float gx = bin_axis_gap(q.x, bx, bin_dims_x, width);
        float in_reach = cutoff + bin_slack;
        if (here != home && gx * gx + gy * gy + gz * gz <= in_reach * in_reach) {
          scan_bin(here, home, q, band, exclude, nearest_only, d1, d2, s1, s2, cutoff, cutoff_squared,
                   entries_planned, entries_visited, searches_ok);
        }
      }
    }
  }
  float dist1 = sqrt(d1);
  float dist2 = sqrt(d2);
  bool has1 = s1 != kNoSite && dist1 < band;
  bool has2 = !nearest_only && s2 != kNoSite && dist2 < band;
  bool complete = bins_visited == bins_planned && entries_visited == entries_planned && searches_ok;
  results[i] = ivec4(complete ? (has1 ? s1 : kNoIndex) : kIncomplete, has2 ? s2 : kNoIndex,
                     floatBitsToInt(has1 ? dist1 : band), floatBitsToInt(has2 ? dist2 : band));
}
