#include "io/scene_source.hpp"

#include "core/errors.hpp"
#include "io/json_check.hpp"
#include "io/mesh_reader.hpp"
#include "io/mesh_reader_detail.hpp"
#include "io/read_util.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <climits>
#include <cstdio>
#include <iterator>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>

namespace vproxq {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string in_quotes(std::string_view s) { return "\"" + std::string(s) + "\""; }

/// A JSON value as it appears in the file, shortened for messages.
std::string shown(const json& v) { return io_detail::abbreviate(v.dump(), 60); }

/// A validated printf frame pattern: prefix, one integer conversion, suffix.
struct FramePattern {
  std::string prefix, suffix;  ///< with "%%" already turned into "%"
  std::string conversion;      ///< e.g. "%04d", safe to hand to snprintf with one int

  std::string format(int value) const {
    char buf[128];
    std::snprintf(buf, sizeof buf, conversion.c_str(), value);
    return prefix + buf + suffix;
  }
};

/// One sequence of frame files: the scene's (one file per frame, all objects), or one
/// object's (per-object sequences). A pattern's file names are made when asked for, so that a
/// large "count" costs nothing until its frames are read.
struct Sequence {
  std::string object_name;            ///< per-object sequences only
  std::vector<fs::path> files;        ///< a "files" list, or a bare mesh file (no pattern)
  std::optional<FramePattern> pattern;  ///< frame k: `base` / pattern->format(first + k)
  fs::path base;                      ///< the scene file's folder
  long long first = 0;
  std::size_t count = 0;              ///< with a pattern
  /// The scene.json key that lists the files ("frames.pattern", or "frames.files" whose items
  /// are named "frames.files[i]"), for messages about one of them; empty for a bare mesh file.
  std::string key;
  bool indexed = false;  ///< the files are a "files" list (their key takes the index)

  std::size_t size() const { return pattern ? count : files.size(); }
  fs::path file(std::size_t k) const {
    return pattern ? base / pattern->format(static_cast<int>(first + static_cast<long long>(k))) : files[k];
  }
  std::string key_of(std::size_t i) const { return indexed ? key + "[" + std::to_string(i) + "]" : key; }
};

/// Parses `pattern`; on error returns false and sets `why`.
bool parse_frame_pattern(const std::string& pattern, FramePattern& out, std::string& why) {
  // Width and precision are capped so the formatted number fits in FramePattern::format.
  constexpr int kMaxWidth = 64;
  int conversions = 0;
  std::string* text = &out.prefix;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      *text += pattern[i];
      continue;
    }
    if (i + 1 < pattern.size() && pattern[i + 1] == '%') {
      *text += '%';
      ++i;
      continue;
    }
    const std::size_t start = i++;
    std::string spec = "%";
    while (i < pattern.size() &&
           std::string_view("-+ 0").find(pattern[i]) != std::string_view::npos) {
      spec += pattern[i++];
    }
    for (int part = 0; part < 2; ++part) {  // width, then .precision
      if (part == 1) {
        if (i >= pattern.size() || pattern[i] != '.') break;
        spec += pattern[i++];
      }
      int number = 0;
      while (i < pattern.size() && pattern[i] >= '0' && pattern[i] <= '9') {
        number = number * 10 + (pattern[i] - '0');
        if (number > kMaxWidth) {
          why = "has a field width or precision above " + std::to_string(kMaxWidth);
          return false;
        }
        spec += pattern[i++];
      }
    }
    if (i >= pattern.size()) {
      why = "ends inside a conversion (\"" + pattern.substr(start) + "\")";
      return false;
    }
    const char c = pattern[i];
    if (c != 'd' && c != 'i' && c != 'u') {
      why = "has the conversion \"" + pattern.substr(start, i - start + 1) +
            "\"; only an integer conversion such as %04d (d, i or u, no length modifier) is "
            "allowed";
      return false;
    }
    spec += 'd';
    if (++conversions > 1) {
      why =
          "has more than one conversion; exactly one integer conversion such as %04d is "
          "needed (write %% for a literal %)";
      return false;
    }
    out.conversion = spec;
    text = &out.suffix;
  }
  if (conversions == 0) {
    why = "has no integer conversion such as %04d";
    return false;
  }
  return true;
}

/// Reads and checks a scene.json. Every error names the scene file and the key.
class SceneParser {
 public:
  explicit SceneParser(const fs::path& scene) : scene_(scene), base_(scene.parent_path()) {}

  [[noreturn]] void fail(const std::string& key, const std::string& why) const {
    throw InputError(scene_.string() + ": " + in_quotes(key) + " " + why);
  }

  /// Rejects keys of `obj` not in `allowed`, suggesting the closest allowed one.
  void check_keys(const json& obj, const std::string& prefix,
                  std::initializer_list<std::string_view> allowed) const {
    for (auto it = obj.begin(); it != obj.end(); ++it) {
      const std::string& key = it.key();
      if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
      std::string msg = scene_.string() + ": unknown key " + in_quotes(prefix + key);
      std::string_view best;
      std::size_t best_d = 3;  // suggest only close matches (typos)
      std::string list;
      for (std::string_view a : allowed) {
        const std::size_t d = edit_distance(key, a);
        if (d < best_d) {
          best_d = d;
          best = a;
        }
        list += (list.empty() ? "" : ", ") + in_quotes(a);
      }
      if (!best.empty()) msg += " (did you mean " + in_quotes(prefix + std::string(best)) + "?)";
      msg += "; allowed " +
             (prefix.empty() ? std::string("top-level")
                             : in_quotes(prefix.substr(0, prefix.size() - 1))) +
             " keys: " + list;
      throw InputError(msg);
    }
  }

  long long integer(const json& v, const std::string& key, long long min, long long max,
                    const std::string& what) const {
    const bool ok = v.is_number_integer() &&
                    (!v.is_number_unsigned() ||
                     v.get<unsigned long long>() <= static_cast<unsigned long long>(max)) &&
                    v.get<long long>() >= min && v.get<long long>() <= max;
    if (!ok) fail(key, "must be " + what + ", got " + shown(v));
    return v.get<long long>();
  }

  std::string string(const json& v, const std::string& key) const {
    if (!v.is_string() || v.get<std::string>().empty()) {
      fail(key, "must be a non-empty string, got " + shown(v));
    }
    // A file name with a NUL would silently name the file before it.
    if (v.get<std::string>().find('\0') != std::string::npos) {
      fail(key, "must not contain a NUL character (\\u0000), got " + shown(v));
    }
    return v.get<std::string>();
  }

  fs::path resolve(const std::string& relative) const { return base_ / relative; }

  /// A "frames" object: {"pattern", "first", "count"} or {"files"}. Whether the files exist is
  /// checked later (require_file(), for the frames a run reads).
  Sequence frames(const json& j, const std::string& key) const {
    if (!j.is_object()) {
      fail(key,
           "must be an object with \"pattern\", \"first\" and \"count\", or with "
           "\"files\", got " +
               shown(j));
    }
    check_keys(j, key + ".", {"pattern", "first", "count", "files"});
    Sequence seq;
    if (j.contains("files")) {
      for (const char* other : {"pattern", "first", "count"}) {
        if (j.contains(other))
          fail(key + ".files",
               std::string("cannot be combined with ") + in_quotes(key + "." + other));
      }
      const json& list = j["files"];
      const std::string fkey = key + ".files";
      if (!list.is_array() || list.empty()) {
        fail(fkey, "must be a non-empty array of file names, got " + shown(list));
      }
      for (std::size_t i = 0; i < list.size(); ++i)
        seq.files.push_back(resolve(string(list[i], fkey + "[" + std::to_string(i) + "]")));
      seq.key = fkey;
      seq.indexed = true;
      return seq;
    }
    if (!j.contains("pattern") || !j.contains("count")) {
      fail(key, "needs either \"pattern\" and \"count\" (and optionally \"first\"), or \"files\"");
    }
    const json& pj = j["pattern"];
    const std::string pattern = string(pj, key + ".pattern");
    FramePattern fp;
    std::string why;
    if (!parse_frame_pattern(pattern, fp, why)) fail(key + ".pattern", why + ", got " + shown(pj));
    const std::string largest = std::to_string(INT_MAX);
    const long long first = j.contains("first") ? integer(j["first"], key + ".first", 0, INT_MAX,
                                                          "an integer from 0 to " + largest)
                                                : 0;
    const long long count = integer(j["count"], key + ".count", 1, INT_MAX, "an integer from 1 to " + largest);
    if (first + count - 1 > INT_MAX) {
      fail(key + ".count", "is too large: " + in_quotes(key + ".first") + " + " +
                               in_quotes(key + ".count") + " exceeds the largest frame number " +
                               std::to_string(INT_MAX));
    }
    seq.pattern = fp;
    seq.base = base_;
    seq.first = first;
    seq.count = static_cast<std::size_t>(count);
    seq.key = key + ".pattern";
    return seq;
  }

  void require_file(const fs::path& file, const std::string& key, std::size_t position) const {
    std::error_code ec;
    const fs::file_status st = fs::status(file, ec);
    if (ec && ec != std::errc::no_such_file_or_directory) {
      fail(key, "frame " + std::to_string(position) + ": cannot access " + file.string() + " (" + ec.message() + ")");
    }
    if (!fs::exists(st)) fail(key, "frame " + std::to_string(position) + ": file not found: " + file.string());
    if (!fs::is_regular_file(st)) {
      fail(key, "frame " + std::to_string(position) + ": not a regular file: " + file.string());
    }
  }

 private:
  fs::path scene_;
  fs::path base_;
};

Topology make_topology(const MeshGroup& g) {
  Topology t;
  t.num_vertices = static_cast<Index>(g.positions.size());
  t.faces = g.faces;
  t.origin = g.origin;
  return t;
}

std::size_t count_faces(const std::vector<MeshGroup>& groups) {
  std::size_t n = 0;
  for (const MeshGroup& g : groups) n += g.faces.size();
  return n;
}

/// Splits the groups of one file into objects by `split`: groups as they are, or each
/// group's connected components ("<group>#<k>").
std::vector<MeshGroup> split_groups(std::vector<MeshGroup> groups, ObjectSplit split) {
  if (split == ObjectSplit::Meshes) return groups;
  std::vector<MeshGroup> parts;
  for (const MeshGroup& g : groups) {
    std::vector<MeshGroup> c = split_components(g);
    std::move(c.begin(), c.end(), std::back_inserter(parts));
  }
  return parts;
}

}  // namespace

std::string query_names_list() {
  std::string s;
  for (const auto q : kQueryNames) s += (s.empty() ? "" : ", ") + std::string(q);
  return s;
}

struct SceneSource::Impl {
  fs::path path;
  std::string name;
  std::vector<std::string> queries;
  std::optional<int> grid;
  std::optional<bool> self;
  ObjectSplit split = ObjectSplit::Meshes;
  bool per_object = false;          ///< "objects" is an array of per-object sequences
  std::vector<Sequence> sequences;  ///< one, or one per object when per_object
  std::size_t frame_count = 0;
  std::vector<Object> statics;  ///< read at open; topology shared by every frame

  // State carried between load_frame() calls (guarded by `mutex`, so frames may be loaded
  // from several threads): the object count of the first frame loaded, and the topologies
  // of the last frame loaded, reused when an object's faces have not changed. Only one
  // frame's topologies are kept, so memory does not grow with the number of frames.
  mutable std::mutex mutex;
  mutable std::optional<std::size_t> expected_objects;
  mutable std::size_t expected_frame = 0;
  mutable std::string expected_file;
  mutable std::vector<std::shared_ptr<const Topology>> previous;
};

namespace {

/// Fills `s` (SceneSource::Impl) from the scene.json at s.path.
template <class SceneImpl>
void parse_scene_json(SceneImpl& s) {
  const std::string text = io_detail::read_whole_file(s.path);
  const std::string where = s.path.string();
  json root;
  // A scene is a few levels deep; far deeper nesting is no scene, and printing or walking it
  // would recurse that deep. A key given twice in one object would silently keep the last.
  constexpr int kMaxDepth = 64;
  {
    std::istringstream in(text);
    const std::string problem = json_structure_problem(in, kMaxDepth, /*unique_keys=*/true);
    if (!problem.empty()) throw InputError(where + ": invalid JSON: " + problem);
  }
  try {
    root = json::parse(text);
  } catch (const json::exception& e) {  // syntax errors, and numbers beyond double's range
    throw InputError(where + ": invalid JSON: " + e.what());
  }
  if (!root.is_object())
    throw InputError(where + ": the scene must be a JSON object, got " + shown(root));
  const SceneParser p(s.path);
  p.check_keys(root, "", {"name", "frames", "objects", "static", "queries", "grid", "self"});

  s.name = root.contains("name") ? p.string(root["name"], "name") : s.path.stem().string();

  if (root.contains("objects")) {
    const json& o = root["objects"];
    if (o.is_string() && o.get<std::string>() == "meshes") {
      s.split = ObjectSplit::Meshes;
    } else if (o.is_string() && o.get<std::string>() == "components") {
      s.split = ObjectSplit::Components;
    } else if (o.is_array() && !o.empty()) {
      s.per_object = true;
    } else {
      p.fail("objects",
             "must be \"meshes\", \"components\" or a non-empty array of "
             "{\"name\", \"frames\"} objects, got " +
                 shown(o));
    }
  }

  if (s.per_object) {
    if (root.contains("frames")) {
      p.fail("frames",
             "cannot be used together with per-object sequences (\"objects\" is an "
             "array; give each object its own \"frames\")");
    }
    const json& list = root["objects"];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string key = "objects[" + std::to_string(i) + "]";
      const json& o = list[i];
      if (!o.is_object()) p.fail(key, "must be an object {\"name\", \"frames\"}, got " + shown(o));
      p.check_keys(o, key + ".", {"name", "frames"});
      if (!o.contains("name")) p.fail(key + ".name", "is missing");
      if (!o.contains("frames")) p.fail(key + ".frames", "is missing");
      const std::string name = p.string(o["name"], key + ".name");
      Sequence seq = p.frames(o["frames"], key + ".frames");
      seq.object_name = name;
      if (i > 0 && seq.size() != s.sequences[0].size()) {
        p.fail(key + ".frames", "has " + std::to_string(seq.size()) +
                                    " frames, but \"objects[0].frames\" has " +
                                    std::to_string(s.sequences[0].size()) +
                                    " (every object needs the same number of frames)");
      }
      s.sequences.push_back(std::move(seq));
    }
  } else {
    if (!root.contains("frames")) p.fail("frames", "is missing");
    s.sequences.push_back(p.frames(root["frames"], "frames"));
  }
  s.frame_count = s.sequences[0].size();

  if (root.contains("queries")) {
    const json& q = root["queries"];
    if (!q.is_array()) p.fail("queries", "must be an array of query names, got " + shown(q));
    if (q.empty()) p.fail("queries", "is empty: list at least one query, or leave the key out (default: distance)");
    for (std::size_t i = 0; i < q.size(); ++i) {
      const std::string key = "queries[" + std::to_string(i) + "]";
      const std::string name = p.string(q[i], key);
      if (std::find(kQueryNames.begin(), kQueryNames.end(), name) == kQueryNames.end()) {
        std::string names;
        for (const auto n : kQueryNames) names += (names.empty() ? "" : ", ") + in_quotes(n);
        p.fail(key, "must be one of " + names + ", got " + shown(q[i]));
      }
      if (std::find(s.queries.begin(), s.queries.end(), name) != s.queries.end()) {
        p.fail(key, "lists " + in_quotes(name) + " a second time");
      }
      s.queries.push_back(name);
    }
  }
  if (root.contains("grid")) {
    const std::string what = "an integer in [1, " + std::to_string(kMaxGridResolution) + "]";
    s.grid = static_cast<int>(p.integer(root["grid"], "grid", 1, kMaxGridResolution, what));
  }
  if (root.contains("self")) {
    if (!root["self"].is_boolean()) p.fail("self", "must be true or false, got " + shown(root["self"]));
    s.self = root["self"].get<bool>();
  }

  if (root.contains("static")) {
    const json& st = root["static"];
    if (!st.is_array()) p.fail("static", "must be an array of file names, got " + shown(st));
    // Static files split like the frames; with per-object sequences, one object per mesh.
    const ObjectSplit split = s.per_object ? ObjectSplit::Meshes : s.split;
    for (std::size_t i = 0; i < st.size(); ++i) {
      const std::string key = "static[" + std::to_string(i) + "]";
      const fs::path file = p.resolve(p.string(st[i], key));
      std::vector<MeshGroup> groups;
      try {
        groups = read_mesh_file(file);
      } catch (const InputError& e) {
        p.fail(key, std::string("cannot be read: ") + e.what());
      }
      if (count_faces(groups) == 0) p.fail(key, "has no triangles: " + file.string());
      for (MeshGroup& g : split_groups(std::move(groups), split)) {
        if (!g.origin.empty()) g.origin.static_file = static_cast<int>(i);
        Object obj;
        obj.name = g.name;
        obj.topology = std::make_shared<const Topology>(make_topology(g));
        obj.positions = std::move(g.positions);
        obj.is_static = true;
        s.statics.push_back(std::move(obj));
      }
    }
  }
}

}  // namespace

SceneSource SceneSource::open(const fs::path& path, FrameFileCheck check) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  if (io_detail::lower_extension(path) != ".json") {
    // A bare mesh file: a one-frame scene, one object per mesh.
    io_detail::require_regular_file(path);
    impl->name = path.stem().string();
    Sequence seq;
    seq.files = {path};
    impl->sequences.push_back(std::move(seq));
    impl->frame_count = 1;
    return SceneSource(std::move(impl));
  }
  parse_scene_json(*impl);
  SceneSource scene(std::move(impl));
  if (check == FrameFileCheck::All) scene.require_frames(0, scene.frame_count());
  return scene;
}

Frame SceneSource::load_frame(std::size_t k) const {
  const Impl& s = *impl_;
  if (k >= s.frame_count) {
    throw std::out_of_range("SceneSource::load_frame: frame " + std::to_string(k) +
                            " requested, the scene has " + std::to_string(s.frame_count));
  }
  Frame frame;
  frame.index = static_cast<int>(k);
  std::vector<MeshGroup> parts;
  if (!s.per_object) {
    const fs::path file = s.sequences[0].file(k);
    frame.files.push_back(file.string());
    std::vector<MeshGroup> groups = read_mesh_file(file);
    if (count_faces(groups) == 0) {
      io_detail::throw_input_error(file, "empty frame: the file has no triangles");
    }
    parts = split_groups(std::move(groups), s.split);
  } else {
    // Each file is one object, whatever groups it holds; its vertices keep file order.
    for (const Sequence& seq : s.sequences) {
      const fs::path file = seq.file(k);
      frame.files.push_back(file.string());
      MeshGroup g = io_detail::read_mesh_file_merged(file);
      if (g.faces.empty()) {
        io_detail::throw_input_error(
            file, "no triangles (object " + in_quotes(seq.object_name) + " needs at least one)");
      }
      g.name = seq.object_name;
      parts.push_back(std::move(g));
    }
  }

  std::vector<std::shared_ptr<const Topology>> topologies(parts.size());
  {
    const std::lock_guard<std::mutex> lock(s.mutex);
    if (s.split == ObjectSplit::Meshes || s.per_object) {
      if (!s.expected_objects) {
        s.expected_objects = parts.size();
        s.expected_frame = k;
        s.expected_file = frame.files.front();
      } else if (*s.expected_objects != parts.size()) {
        throw InputError(frame.files.front() + ": frame " + std::to_string(k) + " has " +
                         std::to_string(parts.size()) + " objects, but frame " +
                         std::to_string(s.expected_frame) + " (" + s.expected_file +
                         ", the first frame loaded) has " + std::to_string(*s.expected_objects) +
                         "; with \"objects\": \"meshes\" every frame must hold the same "
                         "meshes (use \"components\" for objects that break apart)");
      }
    }
    // Reuse the previous frame's topology where the faces are unchanged, so that later
    // stages can tell "same topology" by pointer.
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const MeshGroup& g = parts[i];
      const auto nv = static_cast<Index>(g.positions.size());
      if (i < s.previous.size() && s.previous[i]->num_vertices == nv &&
          s.previous[i]->faces == g.faces && s.previous[i]->origin == g.origin) {
        topologies[i] = s.previous[i];
      } else {
        topologies[i] = std::make_shared<const Topology>(make_topology(g));
      }
    }
    s.previous = topologies;
  }

  frame.objects.reserve(parts.size() + s.statics.size());
  for (std::size_t i = 0; i < parts.size(); ++i) {
    Object obj;
    obj.name = std::move(parts[i].name);
    obj.topology = std::move(topologies[i]);
    obj.positions = std::move(parts[i].positions);
    frame.objects.push_back(std::move(obj));
  }
  frame.objects.insert(frame.objects.end(), s.statics.begin(), s.statics.end());
  return frame;
}

SceneSource::SceneSource(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SceneSource::SceneSource(SceneSource&&) noexcept = default;
SceneSource& SceneSource::operator=(SceneSource&&) noexcept = default;
SceneSource::~SceneSource() = default;

const std::string& SceneSource::name() const { return impl_->name; }
const fs::path& SceneSource::path() const { return impl_->path; }
std::size_t SceneSource::frame_count() const { return impl_->frame_count; }

void SceneSource::require_frames(std::size_t first, std::size_t last) const {
  const Impl& s = *impl_;
  last = std::min(last, s.frame_count);
  const SceneParser p(s.path);
  for (const Sequence& seq : s.sequences) {
    if (seq.key.empty()) continue;  // a bare mesh file, checked by open()
    for (std::size_t k = first; k < last; ++k) p.require_file(seq.file(k), seq.key_of(k), k);
  }
}
const std::vector<std::string>& SceneSource::queries() const { return impl_->queries; }
std::optional<int> SceneSource::grid() const { return impl_->grid; }
std::optional<bool> SceneSource::self() const { return impl_->self; }
ObjectSplit SceneSource::split() const { return impl_->split; }

}  // namespace vproxq
