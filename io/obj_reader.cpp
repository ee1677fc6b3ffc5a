#include "io/obj_reader.hpp"

#include "io/read_util.hpp"

#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <string_view>

namespace vproxq::io_detail {

namespace fs = std::filesystem;

namespace {

/// Statements that carry no geometry we use. Listed so that anything else can be reported as
/// an error (a misnamed or corrupt file should not silently read as an empty mesh).
constexpr std::array<std::string_view, 31> kIgnoredStatements = {
    "vt",       "vn",       "vp",   "l",      "p",      "s",          "usemtl",   "mtllib",
    "cstype",   "deg",      "bmat", "step",   "curv",   "curv2",      "surf",     "parm",
    "trim",     "hole",     "scrv", "sp",     "end",    "con",        "mg",       "bevel",
    "c_interp", "d_interp", "lod",  "maplib", "usemap", "shadow_obj", "trace_obj"};

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

bool is_comment(std::string_view tok) { return !tok.empty() && tok.front() == '#'; }

/// Calls f(line_number, line) for every line of `text` ('\n' or "\r\n" endings).
template <class F>
void for_each_line(const std::string& text, F&& f) {
  std::size_t pos = 0;
  long line_no = 0;
  while (pos < text.size()) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    std::string_view line(text.data() + pos, nl - pos);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    f(++line_no, line);
    pos = nl + 1;
  }
}

struct RawGroup {
  std::string name;         ///< empty: unnamed
  std::vector<Face> faces;  ///< global (file) vertex indices
};

class ObjParser {
 public:
  ObjParser(const fs::path& file, const std::string& text) : file_(file), text_(text) {}

  void parse() {
    // A vertex line and its share of the faces take about 100 bytes; the vector grows past that.
    positions_.reserve(text_.size() / 128);
    groups_.emplace_back();  // faces before any o/g
    for_each_line(text_, [this](long line_no, std::string_view line) {
      line_no_ = line_no;
      parse_line(line);
    });
    // Positive face indices may name vertices defined further down; the largest beyond the
    // vertices read so far is checked now that the count is known. Past it, the lines are read
    // again for the first such index, to name it (the file has been parsed once: its face
    // lines are well formed).
    if (largest_forward_ > static_cast<long long>(positions_.size())) {
      for_each_line(text_, [this](long line_no, std::string_view line) {
        std::string_view rest = line;
        if (next_token(rest) != "f") return;
        for (std::string_view tok = next_token(rest); !tok.empty() && !is_comment(tok); tok = next_token(rest)) {
          long long idx = 0;
          if (parse_integer(tok.substr(0, tok.find('/')), idx) && idx > static_cast<long long>(positions_.size())) {
            line_no_ = line_no;
            fail("face index " + std::to_string(idx) + " out of range (file has " +
                 std::to_string(positions_.size()) + " vertices)");
          }
        }
      });
    }
  }

  std::vector<MeshGroup> result(ObjGroups mode) {
    std::vector<RawGroup*> with_faces;
    for (RawGroup& g : groups_) {
      if (!g.faces.empty()) with_faces.push_back(&g);
    }
    const std::string stem = file_.stem().string();
    std::vector<MeshGroup> out;
    if (mode == ObjGroups::Merge || with_faces.size() <= 1) {
      MeshGroup one;
      const bool named = with_faces.size() == 1 && !with_faces[0]->name.empty() && mode == ObjGroups::Split;
      one.name = named ? with_faces[0]->name : stem;
      one.file_named = !named;
      one.positions = std::move(positions_);
      // Groups follow each other in the file, so concatenating them keeps file order.
      std::size_t n = 0;
      for (const RawGroup* g : with_faces) n += g->faces.size();
      one.faces.reserve(n);
      for (const RawGroup* g : with_faces) {
        one.faces.insert(one.faces.end(), g->faces.begin(), g->faces.end());
      }
      out.push_back(std::move(one));
      return out;
    }
    // Several groups: each keeps the vertices its faces use, in global order. `local` maps a
    // global index to the group's own; it is reset after each group, so the work is
    // proportional to the face corners, not groups x vertices.
    std::vector<Index> local(positions_.size(), kNoIndex);
    std::vector<Index> used;
    // An unnamed group is identified across frames by being the file's only one (see
    // ComponentOrigin); of several, none is (position could pair different meshes).
    const auto unnamed = std::count_if(with_faces.begin(), with_faces.end(), [](const RawGroup* g) { return g->name.empty(); });
    for (std::size_t k = 0; k < with_faces.size(); ++k) {
      RawGroup& g = *with_faces[k];
      used.clear();
      // The vertices the group uses, in global order: marked in `local` and read off in order
      // where their range is within a few times the corners (a group's vertices usually follow
      // each other in the file), else sorted.
      Index lo = std::numeric_limits<Index>::max(), hi = 0;
      for (const Face& f : g.faces)
        for (Index v : f) lo = std::min(lo, v), hi = std::max(hi, v);
      const std::size_t corners = 3 * g.faces.size();
      if (static_cast<std::size_t>(hi - lo) < 4 * corners) {
        for (const Face& f : g.faces)
          for (Index v : f) local[static_cast<std::size_t>(v)] = 0;
        for (Index v = lo; v <= hi; ++v)
          if (local[static_cast<std::size_t>(v)] == 0) used.push_back(v);
      } else {
        for (const Face& f : g.faces) used.insert(used.end(), f.begin(), f.end());
        std::sort(used.begin(), used.end());
        used.erase(std::unique(used.begin(), used.end()), used.end());
      }
      MeshGroup mg;
      mg.name = g.name.empty() ? stem + "_" + std::to_string(k) : g.name;
      mg.file_named = g.name.empty() && unnamed == 1;
      mg.positions.reserve(used.size());
      for (std::size_t i = 0; i < used.size(); ++i) {
        local[static_cast<std::size_t>(used[i])] = static_cast<Index>(i);
        mg.positions.push_back(positions_[static_cast<std::size_t>(used[i])]);
      }
      mg.faces.reserve(g.faces.size());
      for (const Face& f : g.faces) {
        mg.faces.push_back({local[static_cast<std::size_t>(f[0])],
                            local[static_cast<std::size_t>(f[1])],
                            local[static_cast<std::size_t>(f[2])]});
      }
      for (Index v : used) local[static_cast<std::size_t>(v)] = kNoIndex;
      out.push_back(std::move(mg));
    }
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw_input_error(file_, "line " + std::to_string(line_no_) + ": " + what);
  }

  void parse_line(std::string_view line) {
    std::string_view rest = line;
    const std::string_view kw = next_token(rest);
    if (kw.empty() || is_comment(kw)) return;
    if (const std::string_view t = trim(rest); !t.empty() && t.back() == '\\' && kw != "o" && kw != "g") {
      fail("line continuation with '\\' is not supported");
    }
    if (kw == "v") return parse_vertex(rest);
    if (kw == "f") return parse_face(rest);
    if (kw == "o" || kw == "g") {
      // The name ends where a comment starts: at a word that begins with '#', as on v and f
      // lines ("o cloth  # the skirt" names "cloth"); a '#' inside a word is part of the name.
      std::string_view name = rest;
      for (std::size_t i = 0; i < name.size(); ++i)
        if (name[i] == '#' && (i == 0 || is_space(name[i - 1]))) {
          name = name.substr(0, i);
          break;
        }
      groups_.emplace_back();
      groups_.back().name = std::string(trim(name));
      return;
    }
    if (std::find(kIgnoredStatements.begin(), kIgnoredStatements.end(), kw) !=
        kIgnoredStatements.end()) {
      return;
    }
    fail("unknown statement '" + abbreviate(kw) + "'");
  }

  void parse_vertex(std::string_view rest) {
    // x y z, then optionally w (rational weight) or r g b [a] (vertex colour): ignored.
    constexpr int kMaxNumbers = 7;
    Vec3 p;
    int n = 0;
    for (std::string_view tok = next_token(rest); !tok.empty() && !is_comment(tok);
         tok = next_token(rest)) {
      double value = 0;
      if (!parse_double(tok, value)) {
        fail("malformed vertex: '" + abbreviate(tok) + "' is not a number");
      }
      if (n < 3) p[n] = value;
      if (++n > kMaxNumbers) fail("malformed vertex: too many numbers");
    }
    if (n < 3) {
      fail("malformed vertex: expected 3 coordinates, got " + std::to_string(n));
    }
    if (const std::string problem = coordinate_problem(p); !problem.empty())
      fail("vertex " + std::to_string(positions_.size() + 1) + " " + problem);
    if (positions_.size() >= static_cast<std::size_t>(std::numeric_limits<Index>::max()))
      fail("too many vertices (more than " + std::to_string(std::numeric_limits<Index>::max()) +
           "; at most that many are supported)");
    positions_.push_back(p);
  }

  /// Resolves one face corner `i[/t[/n]]` to a 0-based global vertex index.
  Index parse_corner(std::string_view tok) {
    std::array<std::string_view, 3> parts{};
    std::size_t count = 0;
    for (;;) {
      const std::size_t slash = tok.find('/');
      if (count == parts.size()) fail("malformed face corner (too many '/')");
      parts[count++] = tok.substr(0, slash);
      if (slash == std::string_view::npos) break;
      tok.remove_prefix(slash + 1);
    }
    long long idx = 0;
    if (!parse_integer(parts[0], idx)) {
      fail("malformed face corner: vertex index '" + abbreviate(parts[0]) + "' is not an integer");
    }
    for (std::size_t i = 1; i < count; ++i) {
      long long unused = 0;
      if (!parts[i].empty() && !parse_integer(parts[i], unused)) {
        fail("malformed face corner: '" + abbreviate(parts[i]) + "' is not an integer");
      }
    }
    if (count == 2 && parts[1].empty()) fail("malformed face corner: empty texture index");
    if (idx == 0) fail("face index 0 is invalid (OBJ indices start at 1)");
    if (idx > 0) {
      // A vertex further down, or none: parse() checks once the file's count is known.
      largest_forward_ = std::max(largest_forward_, idx);
      return static_cast<Index>(idx - 1);
    }
    const long long resolved = static_cast<long long>(positions_.size()) + idx;
    if (resolved < 0) {
      fail("face index " + std::to_string(idx) + " out of range (relative index; only " +
           std::to_string(positions_.size()) + " vertices are defined before this line)");
    }
    return static_cast<Index>(resolved);
  }

  void parse_face(std::string_view rest) {
    corners_.clear();
    for (std::string_view tok = next_token(rest); !tok.empty() && !is_comment(tok);
         tok = next_token(rest)) {
      corners_.push_back(parse_corner(tok));
    }
    if (corners_.size() < 3) {
      fail("face with " + std::to_string(corners_.size()) + " vertices (a face needs at least 3)");
    }
    std::vector<Face>& faces = groups_.back().faces;
    for (std::size_t i = 1; i + 1 < corners_.size(); ++i) {
      faces.push_back({corners_[0], corners_[i], corners_[i + 1]});
    }
  }

  const fs::path& file_;
  const std::string& text_;
  long line_no_ = 0;
  long long largest_forward_ = 0;  ///< the largest positive face index
  std::vector<Vec3> positions_;
  std::vector<RawGroup> groups_;
  std::vector<Index> corners_;
};

}  // namespace

std::vector<MeshGroup> read_obj(const fs::path& file, ObjGroups groups) {
  const std::string text = read_text_file(file);
  ObjParser parser(file, text);
  parser.parse();
  return parser.result(groups);
}

}  // namespace vproxq::io_detail
