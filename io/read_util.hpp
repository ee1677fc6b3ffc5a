#pragma once
// Small helpers shared by the mesh readers (private to io/): whole-file reading, number
// parsing, and InputError messages that start with the file path.
#include "core/errors.hpp"
#include "core/types.hpp"

#include <filesystem>
#include <string>
#include <string_view>

namespace vproxq::io_detail {

/// Whitespace within a line of a text mesh file: space, tab, CR, form feed, vertical tab.
inline bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

/// Splits off the next is_space()-separated token of `rest` (empty when none is left).
inline std::string_view next_token(std::string_view& rest) {
  std::size_t b = 0;
  while (b < rest.size() && is_space(rest[b])) ++b;
  std::size_t e = b;
  while (e < rest.size() && !is_space(rest[e])) ++e;
  const std::string_view tok = rest.substr(b, e - b);
  rest.remove_prefix(e);
  return tok;
}

/// "<file>: <what>" as an InputError.
[[noreturn]] void throw_input_error(const std::filesystem::path& file, const std::string& what);

/// The whole file as bytes. Throws InputError "<file>: file not found" / "is not a regular
/// file" / "cannot read file (<reason>)".
std::string read_whole_file(const std::filesystem::path& file);

/// Removes a UTF-8 byte order mark (EF BB BF) from the start of `bytes`, if there is one.
void strip_utf8_bom(std::string& bytes);

/// A text mesh file (OBJ, OFF) as read_whole_file() reads it, without a UTF-8 byte order mark,
/// and with classic Mac line endings (CR alone, when the file has no LF at all) turned into LF.
std::string read_text_file(const std::filesystem::path& file);

/// Throws InputError unless `file` exists and is a regular file (same messages as above).
void require_regular_file(const std::filesystem::path& file);

/// Parses all of `token` as a double (decimal or scientific, optional sign, "nan"/"inf"
/// accepted so the caller can report them). Returns false if `token` is not exactly a number.
bool parse_double(std::string_view token, double& out);

/// Parses all of `token` as a decimal integer with optional sign. False if not exactly one.
bool parse_integer(std::string_view token, long long& out);

/// The file's extension, lower case, with the dot (".obj"); empty if none.
std::string lower_extension(const std::filesystem::path& file);

/// "x", "y" or "z" for axis 0, 1, 2.
const char* axis_name(int axis);

/// What is wrong with vertex position `p` ("has a non-finite coordinate (z = nan)", "has a
/// coordinate out of range (x = 1e+70; ...)", "has a coordinate too close to 0 (...)"), or ""
/// when every coordinate is finite and 0 or of magnitude in [kMinCoordinateMagnitude,
/// kMaxCoordinateMagnitude).
std::string coordinate_problem(const Vec3& p);

/// `s` shortened to at most `max_chars` characters (with "..." when cut), control bytes
/// written as \xNN, for messages.
std::string abbreviate(std::string_view s, std::size_t max_chars = 40);

}  // namespace vproxq::io_detail
