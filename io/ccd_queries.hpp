#pragma once
// Reader of CCD query files in the format of the Wang et al. 2021 sample queries
// (tests/data/ccd-queries/README.md): 8 rows per query, each row
// "x_num,x_den,y_num,y_den,z_num,z_den,truth" with integer numerators and denominators (the
// denominators powers of two, so num/den of the two parsed doubles is exact for the data),
// rows ordered start positions (4 points) then end positions (4 points).
#include "core/types.hpp"

#include <array>
#include <filesystem>
#include <vector>

namespace vproxq {

struct CcdQuery {
  /// The 4 points at t = 0 (vf: p, a, b, c; ee: a0, a1, b0, b1).
  std::array<Vec3, 4> start{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  /// The same points at t = 1.
  std::array<Vec3, 4> end{Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()};
  bool truth = false;         ///< the file's ground truth (last column)
  long line = 0;              ///< 1-based line of the query's first row (for messages)
};

/// Reads every query of `file`. Throws InputError "<file>:<line>: <problem>" for a missing or
/// unreadable file, a row without exactly 7 integer fields, a zero denominator, a non-finite
/// coordinate, a truth value other than 0/1 or differing within a query, or a row count that
/// is not a multiple of 8. Empty lines are ignored; an empty file holds 0 queries.
std::vector<CcdQuery> read_ccd_queries(const std::filesystem::path& file);

}  // namespace vproxq
