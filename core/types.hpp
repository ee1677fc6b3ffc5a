#pragma once
// Scalar, index and Eigen aliases used throughout vproxq.
#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <limits>

namespace vproxq {

using Scalar = double;
using Vec3 = Eigen::Matrix<double, 3, 1>;
/// Vertex, triangle and object ids. 32 bits: meshes beyond 2^31 features are out of scope.
using Index = std::int32_t;
/// A triangle as three vertex indices into its object's own vertex array.
using Face = std::array<Index, 3>;
/// Three corner positions.
using Triangle = std::array<Vec3, 3>;

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
inline constexpr Index kNoIndex = -1;

}  // namespace vproxq
