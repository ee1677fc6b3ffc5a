#include "io/off_reader.hpp"

#include "io/read_util.hpp"

#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace vproxq::io_detail {

namespace fs = std::filesystem;

namespace {

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  for (std::string_view tok = next_token(line); !tok.empty(); tok = next_token(line)) {
    words.push_back(tok);
  }
  return words;
}

/// Walks the lines of the text that hold data: blank lines and comments (from `#` to the end
/// of the line) are skipped.
class DataLines {
 public:
  explicit DataLines(const std::string& text) : text_(text) {}

  /// The next line with data (its comment cut off), or false at the end of the text.
  bool next(std::string_view& line) {
    while (pos_ < text_.size()) {
      std::size_t nl = text_.find('\n', pos_);
      if (nl == std::string::npos) nl = text_.size();
      std::string_view l(text_.data() + pos_, nl - pos_);
      pos_ = nl + 1;
      ++line_no_;
      if (const std::size_t hash = l.find('#'); hash != std::string_view::npos) {
        l = l.substr(0, hash);
      }
      std::string_view probe = l;
      if (!next_token(probe).empty()) {
        line = l;
        return true;
      }
    }
    return false;
  }

  /// How many lines with data are left (reads a copy; this walker does not move).
  long long count_remaining() const {
    DataLines copy = *this;
    long long n = 0;
    std::string_view unused;
    while (copy.next(unused)) ++n;
    return n;
  }

  /// The number (1-based) of the line `next` returned last; 0 before the first.
  long line_no() const { return line_no_; }

 private:
  const std::string& text_;
  std::size_t pos_ = 0;
  long line_no_ = 0;
};

/// What a header keyword says; `known` false when `word` is not one.
struct Keyword {
  bool known = false;
  bool four_d = false;  ///< the "4" prefix: 4D vertices
  bool n_dim = false;   ///< the "n" prefix: the dimension follows the keyword
};

/// Parses [ST][C][N][4][n]OFF.
Keyword parse_keyword(std::string_view word) {
  Keyword k;
  auto take = [&word](std::string_view prefix) {
    if (word.substr(0, prefix.size()) != prefix) return false;
    word.remove_prefix(prefix.size());
    return true;
  };
  take("ST");
  take("C");
  take("N");
  k.four_d = take("4");
  k.n_dim = take("n");
  k.known = word == "OFF";
  return k;
}

class OffParser {
 public:
  OffParser(const fs::path& file, const std::string& text) : file_(file), lines_(text) {}

  MeshGroup parse() {
    read_header();
    check_counts_fit();
    MeshGroup out;
    out.name = file_.stem().string();
    out.file_named = true;
    out.positions.reserve(static_cast<std::size_t>(num_vertices_));
    out.faces.reserve(static_cast<std::size_t>(num_faces_));
    std::string_view line;
    for (long long v = 0; v < num_vertices_; ++v) {
      lines_.next(line);  // there are enough lines: check_counts_fit
      out.positions.push_back(parse_vertex(line, v));
    }
    for (long long f = 0; f < num_faces_; ++f) {
      lines_.next(line);
      parse_face(line, f, out.faces);
    }
    if (lines_.next(line)) {
      fail("'" + abbreviate(line) + "' after the " + std::to_string(num_faces_) +
           " faces the header declares (do the header's counts match the data?)");
    }
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw_input_error(file_, "line " + std::to_string(lines_.line_no()) + ": " + what);
  }

  void read_header() {
    std::string_view line;
    if (!lines_.next(line)) throw_input_error(file_, "not an OFF file (it holds no data)");
    std::vector<std::string_view> w = split_words(line);
    const Keyword k = parse_keyword(w[0]);
    if (k.known) {
      if (k.four_d) fail("'" + std::string(w[0]) + "' (4D vertices) is not supported");
      if (k.n_dim) fail("'" + std::string(w[0]) + "' (n-dimensional vertices) is not supported");
      if (w.size() > 1 && w[1] == "BINARY") {
        fail("binary OFF ('" + std::string(w[0]) + " BINARY') is not supported, only ASCII OFF");
      }
      w.erase(w.begin());
      if (w.empty()) {
        if (!lines_.next(line)) {
          throw_input_error(file_, "malformed OFF header: the file ends before the counts line");
        }
        w = split_words(line);
      }
    } else if (w.size() != 3 || !is_count_token(w[0]) || !is_count_token(w[1]) ||
               !is_count_token(w[2])) {
      if (w[0].size() >= 3 && w[0].substr(w[0].size() - 3) == "OFF") {
        fail("unknown OFF keyword '" + abbreviate(w[0]) + "'");
      }
      fail("not an OFF file (expected 'OFF' or the counts 'vertices faces edges', got '" +
           abbreviate(line) + "')");
    }
    // After a keyword, some writers leave out the edge count (which is not used anyway).
    if (w.size() != 3 && !(k.known && w.size() == 2)) {
      fail("malformed OFF header: expected the counts 'vertices faces edges', got " +
           std::to_string(w.size()) + " values");
    }
    num_vertices_ = count(w[0], "vertex");
    num_faces_ = count(w[1], "face");
    if (w.size() == 3) count(w[2], "edge");  // not used, but must be well formed
    if (num_vertices_ > std::numeric_limits<Index>::max()) {
      fail("too many vertices (" + std::to_string(num_vertices_) + "), at most " +
           std::to_string(std::numeric_limits<Index>::max()) + " are supported");
    }
  }

  static bool is_count_token(std::string_view tok) {
    long long v = 0;
    return parse_integer(tok, v) && v >= 0;
  }

  long long count(std::string_view tok, const char* what) const {
    long long v = 0;
    if (!parse_integer(tok, v) || v < 0) {
      fail(std::string("malformed OFF header: the ") + what + " count '" + abbreviate(tok) +
           "' is not a non-negative integer");
    }
    return v;
  }

  /// Every vertex and face takes one line, so the counts cannot exceed the lines left. This
  /// runs before anything is allocated: a corrupt count fails at once instead of exhausting
  /// memory.
  void check_counts_fit() const {
    const long long left = lines_.count_remaining();
    auto lines = [](long long n) { return std::to_string(n) + (n == 1 ? " line" : " lines"); };
    if (num_vertices_ > left) {
      fail("the header declares " + std::to_string(num_vertices_) +
           " vertices, but the file has only " + lines(left) +
           " of data after the header (truncated file or wrong count)");
    }
    if (num_faces_ > left - num_vertices_) {
      fail("the header declares " + std::to_string(num_faces_) +
           (num_faces_ == 1 ? " face" : " faces") + ", but the file has only " +
           lines(left - num_vertices_) + " of data after the " + std::to_string(num_vertices_) +
           " vertex lines (truncated file or wrong count)");
    }
  }

  Vec3 parse_vertex(std::string_view rest, long long v) const {
    Vec3 p = Vec3::Zero();
    int n = 0;
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
      double value = 0;
      if (!parse_double(tok, value)) {
        fail("vertex " + std::to_string(v) + " (0-based): '" + abbreviate(tok) +
             "' is not a number");
      }
      if (n < 3) p[n] = value;
      ++n;
    }
    if (n < 3) {
      fail("vertex " + std::to_string(v) + " (0-based): expected 3 coordinates, got " +
           std::to_string(n));
    }
    if (const std::string problem = coordinate_problem(p); !problem.empty())
      fail("vertex " + std::to_string(v) + " (0-based) " + problem);
    return p;
  }

  void parse_face(std::string_view rest, long long f, std::vector<Face>& faces) {
    const std::string face = "face " + std::to_string(f) + " (0-based)";
    const std::string_view count_tok = next_token(rest);
    long long n = 0;
    if (!parse_integer(count_tok, n)) {
      fail(face + ": the vertex count '" + abbreviate(count_tok) + "' is not an integer");
    }
    if (n < 3) {
      fail(face + " has " + std::to_string(n) + " vertices (a face needs at least 3)");
    }
    corners_.clear();
    for (long long c = 0; c < n; ++c) {
      const std::string_view tok = next_token(rest);
      if (tok.empty()) {
        fail(face + ": expected " + std::to_string(n) + " vertex indices, got " +
             std::to_string(c));
      }
      long long idx = 0;
      if (!parse_integer(tok, idx)) {
        fail(face + ": vertex index '" + abbreviate(tok) + "' is not an integer");
      }
      if (idx < 0 || idx >= num_vertices_) {
        fail(face + ": vertex index " + std::to_string(idx) + " out of range (file has " +
             std::to_string(num_vertices_) + " vertices)");
      }
      corners_.push_back(static_cast<Index>(idx));
    }
    // Colour values (an index into a colour map, or 3 or 4 components) may follow: ignored,
    // but they must be numbers.
    for (std::string_view tok = next_token(rest); !tok.empty(); tok = next_token(rest)) {
      double unused = 0;
      if (!parse_double(tok, unused)) {
        fail(face + ": '" + abbreviate(tok) + "' after the " + std::to_string(n) +
             " vertex indices is not a number");
      }
    }
    for (std::size_t c = 1; c + 1 < corners_.size(); ++c) {
      faces.push_back({corners_[0], corners_[c], corners_[c + 1]});
    }
  }

  const fs::path& file_;
  DataLines lines_;
  long long num_vertices_ = 0;
  long long num_faces_ = 0;
  std::vector<Index> corners_;
};

}  // namespace

MeshGroup read_off(const fs::path& file) {
  const std::string text = read_text_file(file);
  OffParser parser(file, text);
  return parser.parse();
}

}  // namespace vproxq::io_detail
