#pragma once
// Triangle–box overlap (separating axis test), used for conservative voxelization.
#include "core/types.hpp"

namespace vproxq {

/// True unless one of the 13 separating axes (3 box normals, the triangle normal, 9 edge
/// cross products) separates the triangle from the box centred at `center` with half side
/// `half`. Evaluated in double: callers that need a conservative answer pass a half side
/// widened by the rounding slack they can tolerate.
bool triangle_box_overlap(const Triangle& t, const Vec3& center, double half);

}  // namespace vproxq
