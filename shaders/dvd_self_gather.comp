// Stage II of the intra-object query on the GPU (paper 5.2.2): at every sample (voxel, triangle
// f), the distance from the voxel centre to the nearest triangle of f's object that shares no
// vertex with f (f's 1-ring and f itself are skipped by a 3x3 vertex id comparison, as the
// paper's GPU discards adjacent features), capped at the sample's band. One invocation per
// sample. Host side: gl/self_voronoi_backend.{hpp,cpp}; CPU twin: core/voronoi/cpu_self_backend.cpp.
//
// Not compiled on its own: the host appends it to shaders/dvd2_gather.comp (whose main() is
// renamed by a #define), so it shares that shader's storage buffers 0-4, uniforms, distance
// function, bin search and error bound; only the parts below are new:
//   binding 5  results           ivec4 per sample of this batch: float bits of the distance
//                                (band when none below it), nearest triangle (-1 when none),
//                                1 when the loops did not finish (a driver's loop cap, as in
//                                dvd2_gather.comp) else 0, and 0
//   binding 6  sample_triangles  ivec4 per sample of this batch: the sample's triangle f, the
//                                ids [y, z) of the triangles of f's object (consecutive when
//                                triangles are listed in object order; else all of them), 0
//   binding 7  triangle_vertices ivec4 per triangle: its 3 object-local vertex ids, 0
// triangle_info[2t].x (binding 1) is triangle t's object.

layout(std430, binding = 6) readonly buffer SampleTriangles { ivec4 sample_triangles[]; };
layout(std430, binding = 7) readonly buffer TriangleVertices { ivec4 triangle_vertices[]; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= sample_count) {
    return;
  }
  float band = uintBitsToFloat(samples[i].w);
  ivec4 sample_triangle = sample_triangles[i];
  int f = sample_triangle.x;
  int object = triangle_info[2 * f].x;
  ivec3 fv = triangle_vertices[f].xyz;
  ivec3 voxel = ivec3(samples[i].xyz);
  vec3 centre = vec3(voxel) + 0.5;  // in cell units, exact
  vec3 q = centre * cell;

  // Bins overlapping the box centre -+ band (in cells), widened, clamped: as dvd2_gather.
  ivec3 last_voxel = ivec3(dims_x, dims_y, dims_z) - 1;
  float reach = min(band / cell, float(max(dims_x, max(dims_y, dims_z))) + 1.0);
  vec3 widen = (centre + reach + 1.0) * kBinSearchSlack;
  ivec3 bin_lo = min(ivec3(max(floor(centre - reach - widen), vec3(0.0))), last_voxel) / bin_size;
  ivec3 bin_hi = min(ivec3(floor(centre + reach + widen)), last_voxel) / bin_size;

  float best = uintBitsToFloat(0x7F800000u);  // +infinity, squared distance
  int nearest = kNoIndex;
  float cutoff = band + prefilter_margin;
  float cutoff_squared = cutoff * cutoff;
  // What the loops must visit, and what they did (kIncomplete: see dvd2_gather.comp). Every bin
  // of the range is visited: the bins are twice the self band wide, so passing over those
  // beyond the cut-off (as dvd2_gather.comp does) cost more than it saved (skirt: 21 -> 25 ms
  // per frame on llvmpipe).
  uint bins_planned = uint(bin_hi.x - bin_lo.x + 1) * uint(bin_hi.y - bin_lo.y + 1) * uint(bin_hi.z - bin_lo.z + 1);
  uint bins_visited = 0u;
  int entries_planned = 0;
  int entries_visited = 0;
  bool searches_ok = true;
  for (int bz = bin_lo.z; bz <= bin_hi.z; ++bz) {
    for (int by = bin_lo.y; by <= bin_hi.y; ++by) {
      for (int bx = bin_lo.x; bx <= bin_hi.x; ++bx) {
        ivec3 here = ivec3(bx, by, bz);
        ++bins_visited;
        int b = here.x + bin_dims_x * (here.y + bin_dims_y * here.z);
        // Only the run of entries of f's object's triangles is visited (bin_run()).
        ivec3 run = bin_run(bin_offsets[b], bin_offsets[b + 1], sample_triangle.y, sample_triangle.z);
        searches_ok = searches_ok && run.z == 0;
        entries_planned += run.y - run.x;
        for (int j = run.x; j < run.y; ++j) {
          ++entries_visited;
          int t = bin_triangles[j];
          // Visit a triangle once: in the first visited bin of its own range.
          if (triangle_info[2 * t].x != object || max(triangle_info[2 * t].yzw, bin_lo) != here) {
            continue;
          }
          ivec3 tv = triangle_vertices[t].xyz;
          if (any(equal(tv, fv.xxx)) || any(equal(tv, fv.yyy)) || any(equal(tv, fv.zzz))) {
            continue;  // f itself or its 1-ring
          }
          vec3 a = corner(t, 0);
          vec3 b3 = corner(t, 1);
          vec3 c = corner(t, 2);
          vec3 gap = max(max(min(min(a, b3), c) - q, q - max(max(a, b3), c)), vec3(0.0));
          if (dot(gap, gap) > cutoff_squared) {
            continue;
          }
          float d = point_triangle_distance_squared(q, a, b3, c);
          if (d < best || (d == best && t < nearest)) {
            best = d;
            nearest = t;
            cutoff = min(band, sqrt(best)) + prefilter_margin;
            cutoff_squared = cutoff * cutoff;
          }
        }
      }
    }
  }
  float dist = sqrt(best);
  bool has = nearest != kNoIndex && dist < band;
  bool complete = bins_visited == bins_planned && entries_visited == entries_planned && searches_ok;
  results[i] = ivec4(floatBitsToInt(has ? dist : band), has ? nearest : kNoIndex, complete ? 0 : 1, 0);
}
