#pragma once
// A linear pass over JSON text before it is parsed into a document: nesting depth and keys
// given twice in one object. nlohmann's parser callbacks could check both while parsing, but
// its callback parser scans an array for discarded values after each object in it, so an
// array of n objects took time quadratic in n (`vproxq diff` of a 6 MB results file: 45 s).
#include <istream>
#include <string>

namespace vproxq {

/// What is wrong with the structure of the JSON text `in` holds: nested more than `max_depth`
/// arrays and objects deep, (with `unique_keys`) a key given twice in one object, or (with
/// `integers_fit`) a number written as an integer (no '.', no exponent) beyond 64 bits, which
/// the parser would keep only as a double; as a phrase for a message ("nested more than 64
/// levels deep", "the key \"a\" appears twice in one object", "the integer 1...0 does not fit
/// in 64 bits"); "" when none. A syntax error ends the pass with "": the parse that follows
/// reports it. Reads `in` to its end (or to the problem).
std::string json_structure_problem(std::istream& in, int max_depth, bool unique_keys, bool integers_fit = false);

}  // namespace vproxq
