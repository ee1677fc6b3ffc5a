#include "app/check_ccd.hpp"

#include "core/errors.hpp"
#include "core/geometry/ccd.hpp"
#include "io/ccd_queries.hpp"

#include <cstdio>

namespace vproxq {

CheckCcdSummary check_ccd_file(const std::string& file, const std::string& type) {
  if (type != "vf" && type != "ee")
    throw UsageError("--type: expected vf (vertex-face) or ee (edge-edge), got '" + type + "'");
  const bool vf = type == "vf";
  // Read everything first: a malformed file gives its error before any output.
  const std::vector<CcdQuery> queries = read_ccd_queries(file);
  CheckCcdSummary s;
  for (const CcdQuery& q : queries) {
    const CcdResult r = vf ? vertex_face_ccd(q.start, q.end) : edge_edge_ccd(q.start, q.end);
    ++s.queries;
    s.collisions += r.collides;
    if (r.collides && !q.truth) ++s.false_positives;
    if (!r.collides && q.truth) {
      ++s.false_negatives;
      std::fprintf(stderr, "vproxq: false negative: %s:%ld (query %ld)\n", file.c_str(), q.line,
                   s.queries - 1);
    }
  }
  return s;
}

std::string format_check_ccd_summary(const CheckCcdSummary& s) {
  return "queries: " + std::to_string(s.queries) + ", collisions: " + std::to_string(s.collisions) +
         ", false_positives: " + std::to_string(s.false_positives) +
         ", false_negatives: " + std::to_string(s.false_negatives);
}

}  // namespace vproxq
