// Brute-force nearest segment of every query point: a smoke test of the whole GL compute path
// (embedding, defines, SSBOs, dispatch, readback). Host side: gl/point_segment_distance.cpp.
//
// Storage buffers (float32, tightly packed, std430):
//   binding 0  points           3 floats per point:   x y z
//   binding 1  segments         6 floats per segment: ax ay az bx by bz
//   binding 2  nearest_index    per point: the nearest segment; ties go to the smallest index;
//                               0xFFFFFFFF when there are no segments
//   binding 3  nearest_distance per point: its distance (+inf when there are no segments)
// Uniforms: point_count, segment_count, first_point (points are processed in batches of
// at most GL_MAX_COMPUTE_WORK_GROUP_COUNT groups).
// Defines: LOCAL_SIZE, the work group size (default 64).
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif

layout(local_size_x = LOCAL_SIZE) in;

layout(std430, binding = 0) readonly buffer Points { float points[]; };
layout(std430, binding = 1) readonly buffer Segments { float segments[]; };
layout(std430, binding = 2) writeonly buffer NearestIndex { uint nearest_index[]; };
layout(std430, binding = 3) writeonly buffer NearestDistance { float nearest_distance[]; };

uniform uint point_count;
uniform uint segment_count;
uniform uint first_point;

const uint kNoSegment = 0xFFFFFFFFu;

// Squared distance from p to the closed segment [a, b]; a degenerate segment is its point a.
float point_segment_distance_squared(vec3 p, vec3 a, vec3 b) {
  vec3 ab = b - a;
  vec3 ap = p - a;
  float length_squared = dot(ab, ab);
  float t = length_squared > 0.0 ? clamp(dot(ap, ab) / length_squared, 0.0, 1.0) : 0.0;
  vec3 d = ap - t * ab;
  return dot(d, d);
}

void main() {
  uint i = first_point + gl_GlobalInvocationID.x;
  if (i >= point_count) {
    return;
  }
  vec3 p = vec3(points[3u * i], points[3u * i + 1u], points[3u * i + 2u]);
  float best = uintBitsToFloat(0x7F800000u);  // +infinity
  uint best_index = kNoSegment;
  for (uint j = 0u; j < segment_count; ++j) {
    uint s = 6u * j;
    vec3 a = vec3(segments[s], segments[s + 1u], segments[s + 2u]);
    vec3 b = vec3(segments[s + 3u], segments[s + 4u], segments[s + 5u]);
    float d2 = point_segment_distance_squared(p, a, b);
    if (d2 < best) {
      best = d2;
      best_index = j;
    }
  }
  nearest_index[i] = best_index;
  nearest_distance[i] = sqrt(best);
}
