#pragma once
// `vproxq check-ccd FILE.csv --type vf|ee`: runs the elementary CCD test on every query of a
// ground-truth file (format: io/ccd_queries.hpp) and counts the disagreements.
#include <string>

namespace vproxq {

struct CheckCcdSummary {
  long queries = 0;
  long collisions = 0;  ///< queries the test reports as colliding
  long false_positives = 0;
  long false_negatives = 0;
};

/// Reads `file` (InputError naming the file and line on bad input), runs vertex_face_ccd
/// (type "vf") or edge_edge_ccd (type "ee") on each query, prints one line per false negative
/// to stderr and returns the counts. `type` must be "vf" or "ee" (else UsageError).
CheckCcdSummary check_ccd_file(const std::string& file, const std::string& type);

/// The summary line: "queries: N, collisions: C, false_positives: FP, false_negatives: FN".
std::string format_check_ccd_summary(const CheckCcdSummary& s);

}  // namespace vproxq
