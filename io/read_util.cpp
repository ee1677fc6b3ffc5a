#include "io/read_util.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <system_error>

namespace vproxq::io_detail {

namespace fs = std::filesystem;

void throw_input_error(const fs::path& file, const std::string& what) {
  throw InputError(file.string() + ": " + what);
}

void require_regular_file(const fs::path& file) {
  std::error_code ec;
  const fs::file_status st = fs::status(file, ec);
  if (ec || !fs::exists(st)) throw_input_error(file, "file not found");
  if (!fs::is_regular_file(st)) throw_input_error(file, "is not a regular file");
}

std::string read_whole_file(const fs::path& file) {
  require_regular_file(file);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw_input_error(file, std::string("cannot read file (") + std::strerror(errno) + ")");
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw_input_error(file, "cannot read file (cannot determine its size)");
  in.seekg(0, std::ios::beg);
  std::string bytes(static_cast<std::size_t>(size), '\0');
  if (size > 0 && !in.read(bytes.data(), size)) {
    throw_input_error(file, "cannot read file (read error)");
  }
  return bytes;
}

void strip_utf8_bom(std::string& bytes) {
  if (bytes.compare(0, 3, "\xEF\xBB\xBF") == 0) bytes.erase(0, 3);
}

std::string read_text_file(const fs::path& file) {
  std::string text = read_whole_file(file);
  strip_utf8_bom(text);
  if (text.find('\n') == std::string::npos) std::replace(text.begin(), text.end(), '\r', '\n');
  return text;
}

bool parse_double(std::string_view token, double& out) {
  // std::from_chars rejects a leading '+', which some writers emit.
  if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
    token.remove_prefix(1);
  }
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out, std::chars_format::general);
  // ERANGE: a decimal number beyond double's range (from_chars leaves `out` unchanged). Too
  // large becomes +-inf (a non-finite coordinate), too small the smallest double of its sign
  // (a coordinate too close to 0), so that each is reported as what it is, not read as 0.
  if (ec == std::errc::result_out_of_range && ptr == end) {
    const std::string text(token);
    const double v = std::strtod(text.c_str(), nullptr);  // +-HUGE_VAL, or +-0 / subnormal
    out = std::isinf(v) ? v : std::copysign(std::numeric_limits<double>::denorm_min(), v);
    return true;
  }
  return ec == std::errc() && ptr == end;
}

bool parse_integer(std::string_view token, long long& out) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-' && token[1] != '+') {
    token.remove_prefix(1);
  }
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, out);
  return ec == std::errc() && ptr == end;
}

std::string lower_extension(const fs::path& file) {
  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

const char* axis_name(int axis) {
  static const char* const kNames[] = {"x", "y", "z"};
  return kNames[axis];
}

std::string coordinate_problem(const Vec3& p) {
  for (int a = 0; a < 3; ++a) {
    if (std::isfinite(p[a]) && std::abs(p[a]) < kMaxCoordinateMagnitude &&
        (p[a] == 0 || std::abs(p[a]) >= kMinCoordinateMagnitude))
      continue;
    // The shortest text that reads back as the same double ("1e+61", "nan", "-inf").
    char value[64] = {};
    std::to_chars(value, value + sizeof value - 1, p[a]);
    if (!std::isfinite(p[a]))
      return "has a non-finite coordinate (" + std::string(axis_name(a)) + " = " + value + ")";
    if (std::abs(p[a]) >= kMaxCoordinateMagnitude)
      return "has a coordinate out of range (" + std::string(axis_name(a)) + " = " + value +
             "; the supported range is |x| < 2^200, about 1.6e60)";
    if (p[a] != 0 && std::abs(p[a]) < kMinCoordinateMagnitude)
      return "has a coordinate too close to 0 (" + std::string(axis_name(a)) + " = " + value +
             "; nonzero coordinates must be at least 2^-200, about 6.2e-61, in magnitude: write 0)";
  }
  return {};
}

std::string abbreviate(std::string_view s, std::size_t max_chars) {
  const bool cut = s.size() > max_chars;
  if (cut) s = s.substr(0, max_chars);
  // Control bytes as \xNN, so that a binary file read as text cannot put control sequences
  // on the user's terminal (bytes from 0x80 up pass: they may be UTF-8 text).
  std::string out;
  for (const char c : s) {
    const auto b = static_cast<unsigned char>(c);
    if (b >= 0x20 && b != 0x7f) {
      out += c;
    } else {
      static const char* const kHex = "0123456789abcdef";
      out += "\\x";
      out += kHex[b >> 4];
      out += kHex[b & 15];
    }
  }
  return cut ? out + "..." : out;
}

}  // namespace vproxq::io_detail
