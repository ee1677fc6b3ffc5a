#include "io/result_diff.hpp"

#include "core/errors.hpp"
#include "io/json_check.hpp"
#include "io/output.hpp"
#include "io/read_util.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <system_error>

namespace vproxq {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;  // keeps the file's key order, so "first" means first

// Top-level members that legitimately differ between runs of the same scene, and the
// per-frame member that does.
constexpr const char* kIgnoredTopLevel[] = {"version", "settings"};
constexpr const char* kIgnoredPerFrame = "stats";
// Longest value text quoted in a difference message.
constexpr std::size_t kMaxValueText = 80;

Json load_results(const fs::path& file) {
  std::error_code ec;
  if (fs::is_directory(file, ec)) {
    throw InputError("'" + file.string() + "' is a directory, not a results file (give OUT/results.json)");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw InputError("cannot open results file '" + file.string() + "': " + std::strerror(errno));
  }
  Json doc;
  // A results file is a few levels deep; comparing a far deeper document would recurse that
  // deep. A key given twice in one object would compare only its last value, and an integer
  // beyond 64 bits would be compared as a double, not exactly.
  constexpr int kMaxDepth = 64;
  // Read whole first: the check and the parse both go through it, and a pipe (`vproxq diff
  // <(jq . a.json) b.json`) cannot be read twice.
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw InputError("cannot read results file '" + file.string() + "': " + std::strerror(errno));
  // The other file of a run (its 8-byte signature): said so, instead of a JSON parse error that
  // quoted a binary byte.
  if (text.compare(0, 8, "\x89HDF\r\n\x1a\n", 8) == 0)
    throw InputError("'" + file.string() + "' is an HDF5 file (results.h5); vproxq diff compares results.json files");
  // A parser's message may quote the bytes it stopped at: shown as valid UTF-8, control bytes
  // as \xNN, so that a binary file cannot put raw bytes on the terminal.
  auto shown = [](const std::string& message) { return io_detail::abbreviate(valid_utf8(message), 400); };
  {
    std::istringstream check(text);
    const std::string problem = json_structure_problem(check, kMaxDepth, /*unique_keys=*/true, /*integers_fit=*/true);
    if (!problem.empty()) throw InputError("malformed results file '" + file.string() + "': " + shown(problem));
  }
  try {
    doc = Json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw InputError("malformed results file '" + file.string() + "': " + shown(e.what()));
  }
  if (!doc.is_object() || !doc.contains("frames") || !doc["frames"].is_array()) {
    throw InputError("'" + file.string() +
                     "' is not a vproxq results file (no top-level \"frames\" array)");
  }
  return doc;
}

std::string value_text(const Json* value) {
  if (value == nullptr) return "(missing)";
  std::string text = value->dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  if (text.size() > kMaxValueText) text = text.substr(0, kMaxValueText - 3) + "...";
  return text;
}

std::string member_path(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string element_path(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

class Differ {
 public:
  explicit Differ(const DiffOptions& opts) : opts_(opts) {}

  /// The first difference between two whole results files, or nullopt.
  std::optional<std::string> documents(const Json& a, const Json& b) {
    return objects(a, b, "", [](const std::string& key) {
      return std::find_if(std::begin(kIgnoredTopLevel), std::end(kIgnoredTopLevel),
                          [&](const char* k) { return key == k; }) !=
             std::end(kIgnoredTopLevel);
    });
  }

 private:
  // Inside frames[i] the message starts with "frame N (frames[i])" and the path restarts.
  std::string message(const std::string& path, const std::string& detail) const {
    std::string where = context_;
    if (!path.empty()) where += (where.empty() ? "" : ", ") + path;
    return where + ": " + detail;
  }

  std::optional<std::string> mismatch(const std::string& path, const Json* a,
                                      const Json* b) const {
    return message(path, value_text(a) + " vs " + value_text(b));
  }

  bool numbers_equal(const Json& a, const Json& b) const {
    if (a == b) return true;  // exact, integers included
    // Integers (ids, counts, frame numbers; results.json writes every double with a '.' or an
    // exponent) are answers to compare exactly: a tolerance would let triangle 1000001 pass
    // for 1000000, and a double would merge 2^53 and 2^53 + 1.
    if (a.is_number_integer() && b.is_number_integer()) return false;
    const double x = a.get<double>();
    const double y = b.get<double>();
    return std::abs(x - y) <= opts_.atol + opts_.rtol * std::max(std::abs(x), std::abs(y));
  }

  template <class Ignored>
  std::optional<std::string> objects(const Json& a, const Json& b, const std::string& path,
                                     Ignored ignored_here) {
    auto ignored = [&](const std::string& key) {
      return ignored_here(key) || std::find(opts_.ignore.begin(), opts_.ignore.end(), key) != opts_.ignore.end();
    };
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (ignored(it.key())) continue;
      const std::string sub = member_path(path, it.key());
      const auto other = b.find(it.key());
      if (other == b.end()) return mismatch(sub, &it.value(), nullptr);
      const bool frames = path.empty() && it.key() == "frames";
      if (auto d = frames ? frame_list(it.value(), *other) : values(it.value(), *other, sub)) {
        return d;
      }
    }
    for (auto it = b.begin(); it != b.end(); ++it) {
      if (!ignored(it.key()) && a.find(it.key()) == a.end()) {
        return mismatch(member_path(path, it.key()), nullptr, &it.value());
      }
    }
    return std::nullopt;
  }

  std::optional<std::string> frame_list(const Json& a, const Json& b) {
    if (!a.is_array() || !b.is_array()) return values(a, b, "frames");
    if (a.size() != b.size()) {
      return message("frames", std::to_string(a.size()) + " vs " + std::to_string(b.size()) +
                                   " entries");
    }
    for (std::size_t i = 0; i < a.size(); ++i) {
      const Json& fa = a[i];
      context_ = element_path("frames", i);
      if (fa.is_object() && fa.contains("frame") && fa["frame"].is_number()) {
        context_ = "frame " + value_text(&fa["frame"]) + " (" + context_ + ")";
      }
      std::optional<std::string> d;
      if (fa.is_object() && b[i].is_object()) {
        d = objects(fa, b[i], "", [](const std::string& key) { return key == kIgnoredPerFrame; });
      } else {
        d = values(fa, b[i], "");
      }
      if (d) return d;
    }
    context_.clear();
    return std::nullopt;
  }

  std::optional<std::string> values(const Json& a, const Json& b, const std::string& path) {
    if (a.is_number() && b.is_number()) {
      if (numbers_equal(a, b)) return std::nullopt;
      return mismatch(path, &a, &b);
    }
    if (a.type() != b.type()) return mismatch(path, &a, &b);
    if (a.is_object()) return objects(a, b, path, [](const std::string&) { return false; });
    if (a.is_array()) {
      if (a.size() != b.size()) {
        return message(path, std::to_string(a.size()) + " vs " + std::to_string(b.size()) +
                                 " entries");
      }
      for (std::size_t i = 0; i < a.size(); ++i) {
        if (auto d = values(a[i], b[i], element_path(path, i))) return d;
      }
      return std::nullopt;
    }
    if (a != b) return mismatch(path, &a, &b);  // strings, booleans (null == null)
    return std::nullopt;
  }

  const DiffOptions& opts_;
  std::string context_;
};

}  // namespace

DiffOutcome diff_result_files(const fs::path& a, const fs::path& b, const DiffOptions& opts) {
  const Json doc_a = load_results(a);
  const Json doc_b = load_results(b);
  DiffOutcome outcome;
  if (auto d = Differ(opts).documents(doc_a, doc_b)) {
    outcome.equal = false;
    outcome.first_difference = *d;
  }
  return outcome;
}

}  // namespace vproxq
