#include "io/ply_reader.hpp"

#include "io/read_util.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace vproxq::io_detail {

namespace fs = std::filesystem;

namespace {

enum class PlyType : std::uint8_t { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool parse_type(std::string_view s, PlyType& t) {
  struct Name {
    std::string_view name;
    PlyType type;
  };
  // Both the original PLY names and the sized ones are in use.
  static constexpr Name kNames[] = {
      {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
      {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
      {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
      {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
      {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
      {"float64", PlyType::Float64}};
  for (const Name& n : kNames) {
    if (n.name == s) {
      t = n.type;
      return true;
    }
  }
  return false;
}

std::size_t type_size(PlyType t) {
  switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
      return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
      return 2;
    case PlyType::Int32:
    case PlyType::UInt32:
    case PlyType::Float32:
      return 4;
    case PlyType::Float64:
      return 8;
  }
  return 0;
}

bool is_integer_type(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

struct Property {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::UInt8;  ///< lists only
  PlyType type = PlyType::Float32;      ///< the scalar's or the list items' type
};

struct Element {
  std::string name;
  long long count = 0;
  std::vector<Property> props;
};

enum class Format { Ascii, BinaryLittleEndian, BinaryBigEndian };

struct Header {
  Format format = Format::Ascii;
  std::vector<Element> elements;
  std::size_t data_offset = 0;  ///< first byte after the end_header line
};

bool is_space_or_newline(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_space_or_newline(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !is_space_or_newline(line[j])) ++j;
    if (j > i) words.push_back(line.substr(i, j - i));
    i = j;
  }
  return words;
}

Header parse_header(const fs::path& file, const std::string& bytes) {
  Header h;
  std::size_t pos = 0;
  long line_no = 0;
  bool have_format = false;
  bool ended = false;
  auto fail = [&](const std::string& what) {
    throw_input_error(file, "PLY header line " + std::to_string(line_no) + ": " + what);
  };
  while (pos < bytes.size()) {
    std::size_t nl = bytes.find('\n', pos);
    if (nl == std::string::npos) nl = bytes.size();
    std::string_view line(bytes.data() + pos, nl - pos);
    pos = std::min(nl + 1, bytes.size());
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    const std::vector<std::string_view> w = split_words(line);
    if (line_no == 1) {
      if (w.size() != 1 || w[0] != "ply") {
        throw_input_error(file, "not a PLY file (the first line is not 'ply')");
      }
      continue;
    }
    if (w.empty()) continue;
    const std::string_view kw = w[0];
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "end_header") {
      ended = true;
      break;
    }
    if (kw == "format") {
      if (w.size() != 3) fail("malformed format line");
      if (w[1] == "ascii") {
        h.format = Format::Ascii;
      } else if (w[1] == "binary_little_endian") {
        h.format = Format::BinaryLittleEndian;
      } else if (w[1] == "binary_big_endian") {
        h.format = Format::BinaryBigEndian;
      } else {
        fail("unknown format '" + abbreviate(w[1]) + "'");
      }
      if (w[2] != "1.0") fail("unsupported PLY version '" + abbreviate(w[2]) + "' (only 1.0)");
      have_format = true;
    } else if (kw == "element") {
      long long count = 0;
      if (w.size() != 3 || !parse_integer(w[2], count) || count < 0) {
        fail("malformed element line (expected 'element <name> <count>')");
      }
      for (const Element& e : h.elements) {
        if (e.name == w[1]) fail("element '" + std::string(w[1]) + "' declared twice");
      }
      h.elements.push_back({std::string(w[1]), count, {}});
    } else if (kw == "property") {
      if (h.elements.empty()) fail("property before any element");
      Property p;
      if (w.size() == 5 && w[1] == "list") {
        p.is_list = true;
        if (!parse_type(w[2], p.count_type)) fail("unknown type '" + abbreviate(w[2]) + "'");
        if (!parse_type(w[3], p.type)) fail("unknown type '" + abbreviate(w[3]) + "'");
        if (!is_integer_type(p.count_type)) fail("list count type must be an integer type");
        p.name = std::string(w[4]);
      } else if (w.size() == 3 && w[1] != "list") {
        if (!parse_type(w[1], p.type)) fail("unknown type '" + abbreviate(w[1]) + "'");
        p.name = std::string(w[2]);
      } else {
        fail("malformed property line");
      }
      h.elements.back().props.push_back(p);
    } else {
      fail("unknown header keyword '" + abbreviate(kw) + "'");
    }
  }
  if (!ended) throw_input_error(file, "malformed PLY header: no end_header line");
  if (!have_format) throw_input_error(file, "malformed PLY header: no format line");
  h.data_offset = pos;
  return h;
}

/// Where the reader is in the body, for error messages.
struct Where {
  const fs::path* file = nullptr;
  const Element* element = nullptr;
  long long record = 0;

  std::string record_text() const {
    return "element '" + element->name + "' record " + std::to_string(record) + " (0-based) of " +
           std::to_string(element->count);
  }
};

bool host_is_little_endian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

class BinaryCursor {
 public:
  static constexpr bool kBinary = true;

  BinaryCursor(const std::string& bytes, std::size_t offset, bool file_little_endian,
               const Where& where)
      : p_(bytes.data() + offset),
        end_(bytes.data() + bytes.size()),
        swap_(file_little_endian != host_is_little_endian()),
        where_(where) {}

  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

  /// Records have no boundaries in binary: their size is what the types say.
  void begin_record() {}
  void end_record() {}

  /// Throws unless every byte was read: bytes past the header's counts mean the counts or the
  /// types do not describe the file (as values past them do in ascii).
  void expect_end() const {
    if (p_ == end_) return;
    throw_input_error(*where_.file, std::to_string(remaining()) + " byte" + (remaining() == 1 ? "" : "s") +
                                        " after the last element the header declares (do the header's "
                                        "element counts and property types match the data?)");
  }

  double real(PlyType t) {
    if (t == PlyType::Float32) return static_cast<double>(get<float>());
    if (t == PlyType::Float64) return get<double>();
    return static_cast<double>(integer(t));  // every integer type fits a double exactly
  }
  long long integer(PlyType t) {
    switch (t) {
      case PlyType::Int8:
        return get<std::int8_t>();
      case PlyType::UInt8:
        return get<std::uint8_t>();
      case PlyType::Int16:
        return get<std::int16_t>();
      case PlyType::UInt16:
        return get<std::uint16_t>();
      case PlyType::Int32:
        return get<std::int32_t>();
      case PlyType::UInt32:
        return get<std::uint32_t>();
      default:
        break;  // the header check allows only integer types here
    }
    return 0;
  }
  void skip(PlyType t, long long n = 1) {
    const std::size_t size = type_size(t);
    if (n < 0 || static_cast<unsigned long long>(n) > remaining() / size) truncated();
    p_ += size * static_cast<std::size_t>(n);
  }

 private:
  [[noreturn]] void truncated() const {
    throw_input_error(*where_.file,
                      "truncated binary data: the file ends inside " + where_.record_text());
  }
  template <class T>
  T get() {
    if (remaining() < sizeof(T)) truncated();
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, p_, sizeof(T));
    if (swap_) std::reverse(raw, raw + sizeof(T));
    T v;
    std::memcpy(&v, raw, sizeof(T));
    p_ += sizeof(T);
    return v;
  }

  const char* p_;
  const char* end_;
  bool swap_;
  const Where& where_;
};

class AsciiCursor {
 public:
  static constexpr bool kBinary = false;

  AsciiCursor(const std::string& bytes, std::size_t offset, long first_line, const Where& where)
      : p_(bytes.data() + offset),
        end_(bytes.data() + bytes.size()),
        line_(first_line),
        where_(where) {}

  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

  /// In ascii every record is one line (blank lines between records are allowed): a line with
  /// fewer or more values than the element's properties take means the header does not describe
  /// the data (say, vertex rows carrying normals that the header leaves out). Read as one stream
  /// of values, such a file failed far from the cause or, when a longer row and a shorter one
  /// made up for each other, read with wrong coordinates and no error.
  void begin_record() {
    skip_blank(true);
    in_record_ = true;
  }
  void end_record() {
    skip_blank(false);
    in_record_ = false;
    if (p_ == end_ || *p_ == '\n') return;
    const char* b = p_;
    while (p_ < end_ && !is_space_or_newline(*p_)) ++p_;
    throw_input_error(*where_.file, "line " + std::to_string(line_) + ": more values than the header declares for " +
                                        where_.record_text() + ": '" +
                                        abbreviate(std::string_view(b, static_cast<std::size_t>(p_ - b))) +
                                        "' after its last property (each record is one line; does the header "
                                        "list every property of the data?)");
  }

  /// Throws unless only whitespace is left: values past the header's counts mean the counts
  /// do not describe the file.
  void expect_end() {
    skip_blank(true);
    if (p_ != end_) {
      const char* b = p_;
      while (p_ < end_ && !is_space_or_newline(*p_)) ++p_;
      throw_input_error(*where_.file, "line " + std::to_string(line_) + ": '" +
                                          abbreviate(std::string_view(b, static_cast<std::size_t>(p_ - b))) +
                                          "' after the last element the header declares (do the "
                                          "header's element counts match the data?)");
    }
  }

  double real(PlyType t) {
    const std::string_view tok = token();
    if (is_integer_type(t)) {
      long long v = 0;
      if (!parse_integer(tok, v)) malformed(tok, "an integer");
      return static_cast<double>(v);
    }
    double v = 0;
    if (!parse_double(tok, v)) malformed(tok, "a number");
    return v;
  }
  long long integer(PlyType) {
    const std::string_view tok = token();
    long long v = 0;
    if (!parse_integer(tok, v)) malformed(tok, "an integer");
    return v;
  }
  void skip(PlyType t, long long n = 1) {
    for (long long i = 0; i < n; ++i) real(t);
  }

 private:
  /// Skips whitespace, and line ends too when `newlines` (else stops at one).
  void skip_blank(bool newlines) {
    while (p_ < end_ && is_space_or_newline(*p_) && (newlines || *p_ != '\n')) {
      if (*p_ == '\n') ++line_;
      ++p_;
    }
  }
  std::string_view token() {
    skip_blank(!in_record_);
    if (p_ < end_ && *p_ == '\n') {
      throw_input_error(*where_.file, "line " + std::to_string(line_) + ": fewer values than the header declares for " +
                                          where_.record_text() +
                                          ": the line ends before its last property (each record is one line; "
                                          "does the header match the data?)");
    }
    if (p_ == end_) {
      throw_input_error(*where_.file, "unexpected end of file inside " + where_.record_text());
    }
    const char* b = p_;
    while (p_ < end_ && !is_space_or_newline(*p_)) ++p_;
    return std::string_view(b, static_cast<std::size_t>(p_ - b));
  }
  [[noreturn]] void malformed(std::string_view tok, const char* expected) const {
    throw_input_error(*where_.file, "line " + std::to_string(line_) + ": expected " + expected +
                                        " in " + where_.record_text() + ", got '" +
                                        abbreviate(tok) + "'");
  }

  const char* p_;
  const char* end_;
  long line_;
  const Where& where_;
  bool in_record_ = false;
};

int find_property(const Element& e, std::string_view name) {
  for (std::size_t i = 0; i < e.props.size(); ++i) {
    if (e.props[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

/// The face element's index list: `vertex_indices`, else `vertex_index`; -1 if neither.
int face_list_property(const Element& e) {
  const int list = find_property(e, "vertex_indices");
  return list >= 0 ? list : find_property(e, "vertex_index");
}

/// Checks what the body reader relies on, before any data is read: a vertex element with
/// scalar x, y, z, and a face element (if any) with an integer index list.
void check_elements(const fs::path& file, const Header& h) {
  bool has_vertex = false;
  for (const Element& e : h.elements) {
    for (std::size_t i = 0; i < e.props.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (e.props[j].name == e.props[i].name)
          throw_input_error(file, "malformed PLY header: element '" + abbreviate(e.name) +
                                      "' declares property '" + abbreviate(e.props[i].name) + "' twice");
    // Triangle strips would be skipped like any unknown element, losing the mesh's faces.
    if ((e.name == "tristrips" || e.name == "tristrip") && e.count > 0)
      throw_input_error(file, "element '" + e.name + "' (triangle strips) is not supported: "
                              "store the faces as a 'face' element with 'vertex_indices' lists");
  }
  for (const Element& e : h.elements) {
    if (e.name == "vertex") {
      has_vertex = true;
      for (int a = 0; a < 3; ++a) {
        const int p = find_property(e, axis_name(a));
        if (p < 0) {
          throw_input_error(
              file, std::string("the vertex element has no '") + axis_name(a) + "' property");
        }
        if (e.props[static_cast<std::size_t>(p)].is_list) {
          throw_input_error(file, std::string("vertex property '") + axis_name(a) +
                                      "' is a list, expected a scalar");
        }
      }
    } else if (e.name == "face") {
      const int list = face_list_property(e);
      if (list < 0 || !e.props[static_cast<std::size_t>(list)].is_list) {
        throw_input_error(file, "the face element has no 'vertex_indices' list");
      }
      if (!is_integer_type(e.props[static_cast<std::size_t>(list)].type)) {
        throw_input_error(file, "face vertex indices must have an integer type");
      }
    }
  }
  if (!has_vertex) throw_input_error(file, "malformed PLY header: no vertex element");
}

/// A lower bound on the bytes one record of `e` takes: each value at least one character in
/// ascii; scalars at their size and lists at their count's size in binary.
std::size_t min_record_bytes(const Element& e, bool binary) {
  std::size_t n = 0;
  for (const Property& p : e.props) {
    n += !binary ? 1 : type_size(p.is_list ? p.count_type : p.type);
  }
  return std::max<std::size_t>(n, 1);
}

/// Reads the body element by element. `Cursor` is BinaryCursor or AsciiCursor.
template <class Cursor>
void read_body(const fs::path& file, const Header& h, Cursor& in, Where& where, MeshGroup& out) {
  Index num_vertices = 0;
  for (const Element& e : h.elements) {
    if (e.name == "vertex") {
      if (e.count > std::numeric_limits<Index>::max()) {
        throw_input_error(file, "too many vertices (" + std::to_string(e.count) + ")");
      }
      num_vertices = static_cast<Index>(e.count);
    }
  }
  std::vector<Index> corners;
  for (const Element& e : h.elements) {
    where.element = &e;
    // Reserve for the declared count, but never more records than the bytes left could hold,
    // so that a corrupt header cannot make us allocate far more than the file's size.
    const auto reservable = static_cast<std::size_t>(
        std::min<unsigned long long>(static_cast<unsigned long long>(e.count),
                                     in.remaining() / min_record_bytes(e, Cursor::kBinary)));
    if (e.name == "vertex") {
      int axis_prop[3];
      for (int a = 0; a < 3; ++a) axis_prop[a] = find_property(e, axis_name(a));
      out.positions.reserve(reservable);
      for (where.record = 0; where.record < e.count; ++where.record) {
        in.begin_record();
        Vec3 p = Vec3::Zero();
        for (std::size_t i = 0; i < e.props.size(); ++i) {
          const Property& prop = e.props[i];
          if (prop.is_list) {
            in.skip(prop.type, in.integer(prop.count_type));
            continue;
          }
          const int ii = static_cast<int>(i);
          const int axis = ii == axis_prop[0]   ? 0
                           : ii == axis_prop[1] ? 1
                           : ii == axis_prop[2] ? 2
                                                : -1;
          if (axis >= 0) {
            p[axis] = in.real(prop.type);
          } else {
            in.skip(prop.type);
          }
        }
        in.end_record();
        if (const std::string problem = coordinate_problem(p); !problem.empty())
          throw_input_error(file, "vertex " + std::to_string(where.record) + " (0-based) " + problem);
        out.positions.push_back(p);
      }
    } else if (e.name == "face") {
      const int list = face_list_property(e);
      out.faces.reserve(reservable);
      for (where.record = 0; where.record < e.count; ++where.record) {
        in.begin_record();
        for (std::size_t i = 0; i < e.props.size(); ++i) {
          const Property& prop = e.props[i];
          if (static_cast<int>(i) != list) {
            if (prop.is_list) {
              in.skip(prop.type, in.integer(prop.count_type));
            } else {
              in.skip(prop.type);
            }
            continue;
          }
          const long long n = in.integer(prop.count_type);
          if (n < 3) {
            throw_input_error(file, "face " + std::to_string(where.record) + " (0-based) has " +
                                        std::to_string(n) + " vertices (a face needs at least 3)");
          }
          corners.clear();
          for (long long c = 0; c < n; ++c) {
            const long long idx = in.integer(prop.type);
            if (idx < 0 || idx >= num_vertices) {
              throw_input_error(file, "face " + std::to_string(where.record) +
                                          " (0-based): vertex index " + std::to_string(idx) +
                                          " out of range (file has " +
                                          std::to_string(num_vertices) + " vertices)");
            }
            corners.push_back(static_cast<Index>(idx));
          }
          for (std::size_t c = 1; c + 1 < corners.size(); ++c) {
            out.faces.push_back({corners[0], corners[c], corners[c + 1]});
          }
        }
        in.end_record();
      }
    } else {
      // An element without properties has empty records: no line of its own to look for.
      if (e.props.empty()) continue;
      for (where.record = 0; where.record < e.count; ++where.record) {
        in.begin_record();
        for (const Property& prop : e.props) {
          if (prop.is_list) {
            in.skip(prop.type, in.integer(prop.count_type));
          } else {
            in.skip(prop.type);
          }
        }
        in.end_record();
      }
    }
  }
}

}  // namespace

MeshGroup read_ply(const fs::path& file) {
  std::string bytes = read_whole_file(file);
  strip_utf8_bom(bytes);
  const Header h = parse_header(file, bytes);
  check_elements(file, h);

  MeshGroup out;
  out.name = file.stem().string();
  out.file_named = true;
  Where where;
  where.file = &file;
  if (h.format == Format::Ascii) {
    const long header_lines = static_cast<long>(std::count(
        bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(h.data_offset), '\n'));
    AsciiCursor in(bytes, h.data_offset, header_lines + 1, where);
    read_body(file, h, in, where, out);
    in.expect_end();
  } else {
    BinaryCursor in(bytes, h.data_offset, h.format == Format::BinaryLittleEndian, where);
    read_body(file, h, in, where, out);
    in.expect_end();
  }
  return out;
}

}  // namespace vproxq::io_detail
