#pragma once
// Scalar, index and Eigen aliases used throughout vproxq.
#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace vproxq {

using Scalar = double;
using Vec3 = Eigen::Matrix<double, 3, 1>;
/// Vertex, triangle and object ids. 32 bits: meshes beyond 2^31 features are out of scope.
using Index = std::int32_t;
/// A triangle as three vertex indices into its object's own vertex array.
using Face = std::array<Index, 3>;
/// Three corner positions.
using Triangle = std::array<Vec3, 3>;

/// Whether item i (an object of a frame, a triangle of an object) is marked in a per-item flag
/// vector: false without one, and for items past its end.
inline bool marked(const std::vector<std::uint8_t>* mask, std::size_t i) {
  return mask != nullptr && i < mask->size() && (*mask)[i] != 0;
}

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
inline constexpr Index kNoIndex = -1;
/// Vertex coordinates must be finite and 0 or of magnitude in [2^-200, 2^200) (about 6.2e-61
/// to 1.6e60): the exact predicates are exact, and the distance arithmetic free of overflow and
/// of harmful underflow, only in that range (core/geometry/predicates.hpp); the mesh readers
/// reject anything else as an input error.
inline constexpr double kMinCoordinateMagnitude = 0x1p-200;
inline constexpr double kMaxCoordinateMagnitude = 0x1p200;

}  // namespace vproxq
