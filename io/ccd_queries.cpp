#include "io/ccd_queries.hpp"

#include "io/read_util.hpp"

#include <cmath>
#include <cstdlib>
#include <string>
#include <string_view>

namespace vproxq {
namespace {

using io_detail::throw_input_error;

[[noreturn]] void fail(const std::filesystem::path& file, long line, const std::string& what) {
  throw_input_error(file, "line " + std::to_string(line) + ": " + what);
}

/// An optional sign then decimal digits only (the file's numbers are integers of any length).
bool is_integer_token(std::string_view s) {
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.remove_prefix(1);
  if (s.empty()) return false;
  for (char c : s)
    if (c < '0' || c > '9') return false;
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

}  // namespace

std::vector<CcdQuery> read_ccd_queries(const std::filesystem::path& file) {
  const std::string text = io_detail::read_whole_file(file);
  std::vector<CcdQuery> out;
  CcdQuery q;
  int row = 0;  // row within the current query
  long line = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    const std::string_view content = trim(std::string_view(text).substr(pos, eol - pos));
    pos = eol + 1;
    ++line;
    if (content.empty()) continue;
    std::string_view fields[7];
    int n = 0;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = content.find(',', start);
      const std::string_view f = trim(content.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start));
      if (n < 7) fields[n] = f;
      ++n;
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    if (n != 7)
      fail(file, line, "expected 7 comma-separated integers (x_num,x_den,y_num,y_den,z_num,z_den,truth), found " +
                           std::to_string(n) + " fields");
    // Numerators and denominators may have any number of digits: each is read in long
    // double (range about 1e+-4932, so 10^400 / 10^400 is 1, not inf / inf), and the quotient
    // is checked against the coordinate range there, before it is rounded to double (where
    // 10^300 / 10^400 would underflow to 0).
    long double v[6];
    for (int k = 0; k < 6; ++k) {
      if (!is_integer_token(fields[k]))
        fail(file, line, "field " + std::to_string(k + 1) + " '" + io_detail::abbreviate(fields[k]) + "' is not an integer");
      const std::string digits(fields[k]);
      v[k] = std::strtold(digits.c_str(), nullptr);
      if (!std::isfinite(v[k]))
        fail(file, line, "field " + std::to_string(k + 1) + " '" + io_detail::abbreviate(fields[k]) + "' is too large");
    }
    Vec3 p;
    for (int k = 0; k < 3; ++k) {
      if (v[2 * k + 1] == 0) fail(file, line, std::string("zero denominator for ") + io_detail::axis_name(k));
      const long double q = v[2 * k] / v[2 * k + 1];
      const long double m = std::fabs(q);
      const std::string what = std::string("coordinate ") + io_detail::axis_name(k) + " = " +
                               io_detail::abbreviate(fields[2 * k]) + "/" + io_detail::abbreviate(fields[2 * k + 1]);
      if (m >= 0x1p200L)
        fail(file, line, what + " is out of range (the supported range is |x| < 2^200, about 1.6e60)");
      if (q != 0 && m < 0x1p-200L)
        fail(file, line, what + " is too close to 0 (nonzero coordinates must be at least 2^-200, about 6.2e-61, in magnitude)");
      p[k] = static_cast<double>(q);
    }
    // The kernel's guarantees hold for the coordinate range every reader enforces.
    if (const std::string problem = io_detail::coordinate_problem(p); !problem.empty())
      fail(file, line, "the point " + problem);
    if (fields[6] != "0" && fields[6] != "1")
      fail(file, line, "truth (field 7) must be 0 or 1, found '" + io_detail::abbreviate(fields[6]) + "'");
    const bool truth = fields[6] == "1";
    if (row == 0) {
      q = CcdQuery{};
      q.line = line;
      q.truth = truth;
    } else if (truth != q.truth) {
      fail(file, line, "truth differs from the query's first row (line " + std::to_string(q.line) + ")");
    }
    (row < 4 ? q.start[static_cast<std::size_t>(row)] : q.end[static_cast<std::size_t>(row - 4)]) = p;
    if (++row == 8) {
      out.push_back(q);
      row = 0;
    }
  }
  if (row != 0)
    fail(file, line, "the file ends inside a query (" + std::to_string(row) +
                         " of its 8 rows, starting at line " + std::to_string(q.line) + ")");
  return out;
}

}  // namespace vproxq
