// CCD Stage II (core/voronoi/ccd_stage2.hpp): the voxels of each (triangle, time slot) record
// and the co-occupancy of its keys. Integer work only, so the output equals the CPU backend's
// exactly. Host side: gl/ccd_voxel_backend.cpp. One invocation per record.
//
// Storage buffers (std430, tightly packed):
//   binding 0  records      24 int per record: lo xyz, hi xyz, axis[3][3], below[3], above[3],
//                           key_base (bits of a uint), 2 unused
//   binding 1  room         per record: where its keys start in `keys` (this batch's offset)
//   binding 2  objects      per record: the object id of its triangle
//   binding 3  keys         out (pass 0): the record's keys, ascending, from room[r]
//   binding 4  counts       out (pass 0): the number of keys of each record, or kIncomplete
//                           when the loops did not visit the whole box (see below)
//   binding 5  table        per key: 0 unmarked, object + 1 marked by that object only,
//                           0xFFFFFFFF by two or more (zeroed by the host before pass 0)
//   binding 6  foreign      out (pass 1): 1 when one of the record's keys is in two objects,
//                           2 when the loops did not visit the whole box
// Some drivers cap the loop iterations of one invocation (Mesa's llvmpipe stops every loop
// after 65535 iterations in all, silently): each invocation counts the voxels it visited and
// reports a box it did not finish, so that the host can redo the work another way.
// Uniforms: dims_x, dims_y (grid size per slot), record_count (this batch), pass (0: mark, 1: foreign),
// cooccupancy (0: no table, pass 0 only lists keys).
// Voxel (x, y, z) is kept iff below[a] < axis[a] . (x, y, z) < above[a] for a = 0, 1, 2: all
// values stay below 2^27 in magnitude (the host's caps), so int32 is exact.
#ifndef LOCAL_SIZE
#define LOCAL_SIZE 64
#endif

layout(local_size_x = LOCAL_SIZE) in;

layout(std430, binding = 0) readonly buffer Records { int records[]; };
layout(std430, binding = 1) readonly buffer Room { uint room[]; };
layout(std430, binding = 2) readonly buffer Objects { int objects[]; };
layout(std430, binding = 3) writeonly buffer Keys { uint keys[]; };
layout(std430, binding = 4) writeonly buffer Counts { uint counts[]; };
layout(std430, binding = 5) coherent buffer Table { uint table[]; };
layout(std430, binding = 6) writeonly buffer Foreign { uint foreign[]; };

uniform uint dims_x;  // voxels per row
uniform uint dims_y;  // rows per layer
uniform uint record_count;
uniform uint pass;
uniform uint cooccupancy;

const uint kShared = 0xFFFFFFFFu;
const uint kIncomplete = 0xFFFFFFFFu;

void main() {
  uint r = gl_GlobalInvocationID.x;
  if (r >= record_count) return;
  int base = int(r) * 24;
  ivec3 lo = ivec3(records[base], records[base + 1], records[base + 2]);
  ivec3 hi = ivec3(records[base + 3], records[base + 4], records[base + 5]);
  ivec3 axis[3];
  for (int a = 0; a < 3; ++a)
    axis[a] = ivec3(records[base + 6 + 3 * a], records[base + 7 + 3 * a], records[base + 8 + 3 * a]);
  ivec3 below = ivec3(records[base + 15], records[base + 16], records[base + 17]);
  ivec3 above = ivec3(records[base + 18], records[base + 19], records[base + 20]);
  uint key_base = uint(records[base + 21]);
  uint me = uint(objects[r]) + 1u;
  uint n = 0u;
  uint visited = 0u;
  bool shared_key = false;
  for (int z = lo.z; z <= hi.z; ++z) {
    for (int y = lo.y; y <= hi.y; ++y) {
      for (int x = lo.x; x <= hi.x; ++x) {
        ++visited;
        ivec3 d = ivec3(axis[0].x * x + axis[0].y * y + axis[0].z * z,
                        axis[1].x * x + axis[1].y * y + axis[1].z * z,
                        axis[2].x * x + axis[2].y * y + axis[2].z * z);
        if (!all(lessThan(below, d)) || !all(lessThan(d, above))) continue;
        uint key = key_base + uint(x) + dims_x * (uint(y) + dims_y * uint(z));
        if (pass == 0u) {
          keys[room[r] + n] = key;
          if (cooccupancy != 0u) {
            // Order-independent final state: object + 1 iff only that object marks the key.
            uint seen = atomicCompSwap(table[key], 0u, me);
            if (seen != 0u && seen != me) atomicExchange(table[key], kShared);
          }
        } else if (table[key] == kShared) {
          shared_key = true;
        }
        ++n;
      }
    }
  }
  ivec3 size = max(hi - lo + 1, ivec3(0));
  bool complete = visited == uint(size.x) * uint(size.y) * uint(size.z);
  if (pass == 0u)
    counts[r] = complete ? n : kIncomplete;
  else
    foreign[r] = complete ? (shared_key ? 1u : 0u) : 2u;
}
