#include "io/hdf5_writer.hpp"

#include "core/errors.hpp"
#include "io/hdf5_util.hpp"
#include "io/output.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace vproxq::detail {

namespace {

using h5::Handle;

// In-memory rows of the compound datasets; the file types are packed little-endian copies.
struct ObjectRow {
  std::int32_t id;
  std::int32_t vertices;
  std::int32_t triangles;
  std::uint8_t is_static;
};

struct InterRow {
  std::int32_t object;
  std::int32_t nearest_object;
  double distance;
  std::int32_t tri_a;
  std::int32_t tri_b;
  double point_a[3];
  double point_b[3];
  std::uint8_t kind;  // field "case"
};

struct PairRow {  // one intersecting triangle pair
  std::int32_t object_a, tri_a, object_b, tri_b;
};

struct PdRow {  // one object pair's penetration depth
  std::int32_t object_a, object_b;
  std::uint8_t status;  // PdStatus code (README)
  double depth;         // NaN unless status is 0 (ok)
  double direction[3];
  std::int32_t deepest_object, deepest_vertex;  // -1: direction from a face normal
  double deepest_point[3], nearest_point[3];
  std::uint8_t reason;                // PdReason code (README), 0 unless self_intersection
  std::int32_t reason_a, reason_b;    // its vertex (and -1) or triangle pair; -1 = none
};

struct FeatureRow {  // one overlapping feature of one pd row
  std::int32_t pair, object, id;
  std::uint8_t side;  // which of the entry's two lists (objects[side]): a self entry's two
                      // lists are of one object, the deepest vertex's piece of sheet and the rest
};

// One row of distance/intra: triangle `triangle` of object `object` and its nearest
// non-adjacent triangle; one row of distance/intra_min: an object's minimum.
struct IntraRow {
  std::int32_t object;
  std::int32_t triangle;
  std::int32_t nearest;
  double distance;
  double point_a[3];
  double point_b[3];
  std::uint8_t kind;  // field "case"
};

// CCD rows (ccd/vf, ccd/ee, ccd/pairs).
struct CcdVfRow {
  std::int32_t object_v;
  std::int32_t vertex;
  std::int32_t object_f;
  std::int32_t face;
  double toi;
};

struct CcdEeRow {
  std::int32_t object_a;
  std::int32_t a0;
  std::int32_t a1;
  std::int32_t object_b;
  std::int32_t b0;
  std::int32_t b1;
  double toi;
};

struct CcdPairRow {
  std::int32_t object_a;
  std::int32_t object_b;
  double toi;
  std::uint64_t primitive_pairs;
};

// File codes of TriangleDistanceCase, fixed by the file format (not by the enum's order).
std::uint8_t case_code(TriangleDistanceCase kind) {
  switch (kind) {
    case TriangleDistanceCase::Intersecting: return 0;
    case TriangleDistanceCase::VertexFace: return 1;
    case TriangleDistanceCase::FaceVertex: return 2;
    case TriangleDistanceCase::EdgeEdge: return 3;
  }
  return kHdf5CaseNone;
}

std::string frame_group_name(int frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06d", frame);
  return name;
}

std::string join(const std::vector<std::string>& parts, const char* separator) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) {
    if (i > 0) out += separator;
    out += parts[i];
  }
  return out;
}

}  // namespace

struct Hdf5ResultWriter::Impl {
  std::string path;
  Handle file_access;
  Handle file;
  Handle frames;
  int frames_since_open = 0;
  Handle string_type;
  Handle object_mem_type, object_file_type;
  Handle inter_mem_type, inter_file_type;
  Handle pair_mem_type, pair_file_type;
  Handle pd_mem_type, pd_file_type;
  Handle vertex_feature_mem_type, vertex_feature_file_type;
  Handle triangle_feature_mem_type, triangle_feature_file_type;
  Handle intra_mem_type, intra_file_type;
  Handle ccd_vf_mem_type, ccd_vf_file_type, ccd_ee_mem_type, ccd_ee_file_type;
  Handle ccd_pair_mem_type, ccd_pair_file_type;
  Handle transfer;        ///< dataset transfer list, its buffer sized to each write
  Handle group_creation;  ///< keeps up to kCompactAttributes attributes in the object header

  // HDF5 keeps bookkeeping for an open file (free-space sections and the like) that grows
  // with every object written, a few hundred bytes a frame; closing and reopening the file now and
  // then releases it, so that memory stays flat however many frames a run writes.
  static constexpr int kFramesPerOpen = 1000;

  void reopen() {
    close_checked(frames, "H5Gclose", "/frames");
    close_checked(file, "H5Fclose", "");
    file = Handle(check_id(H5Fopen(path.c_str(), H5F_ACC_RDWR, file_access.get()), "H5Fopen", ""),
                  H5Fclose);
    frames = Handle(check_id(H5Gopen2(file.get(), "frames", H5P_DEFAULT), "H5Gopen2", "/frames"),
                    H5Gclose);
    frames_since_open = 0;
  }

  [[noreturn]] void fail(const char* call, const std::string& object) const {
    throw RuntimeError("HDF5: " + h5::failure_text(call, path, object));
  }
  hid_t check_id(hid_t id, const char* call, const std::string& object) const {
    if (id < 0) fail(call, object);
    return id;
  }
  void check_ok(herr_t status, const char* call, const std::string& object) const {
    if (status < 0) fail(call, object);
  }
  void close_checked(Handle& handle, const char* call, const std::string& object) const {
    check_ok(handle.close(), call, object);
  }

  // One compound member: its name, where it lies in memory, and its memory and file types.
  struct Member {
    const char* name;
    std::size_t offset;
    hid_t mem_type;
    hid_t file_type;
  };

  // Builds the native memory type and the packed file type of one compound row.
  void build_compound(const std::vector<Member>& members, std::size_t mem_size, Handle& mem,
                      Handle& packed) const {
    mem = Handle(check_id(H5Tcreate(H5T_COMPOUND, mem_size), "H5Tcreate", "compound"), H5Tclose);
    std::size_t file_size = 0;
    for (const Member& m : members) {
      check_ok(H5Tinsert(mem.get(), m.name, m.offset, m.mem_type), "H5Tinsert", m.name);
      file_size += H5Tget_size(m.file_type);
    }
    packed = Handle(check_id(H5Tcreate(H5T_COMPOUND, file_size), "H5Tcreate", "compound"),
                    H5Tclose);
    std::size_t offset = 0;
    for (const Member& m : members) {
      check_ok(H5Tinsert(packed.get(), m.name, offset, m.file_type), "H5Tinsert", m.name);
      offset += H5Tget_size(m.file_type);
    }
  }

  void build_property_lists() {
    transfer = Handle(check_id(H5Pcreate(H5P_DATASET_XFER), "H5Pcreate", "transfer list"),
                      H5Pclose);
    group_creation = Handle(check_id(H5Pcreate(H5P_GROUP_CREATE), "H5Pcreate", "group list"),
                            H5Pclose);
    // The stats group has up to 19 attributes; past HDF5's default of 8 each group would get its own
    // dense attribute storage (a fractal heap and a B-tree), slower and larger on disk.
    constexpr unsigned kCompactAttributes = 24;
    constexpr unsigned kDenseAttributes = 20;
    check_ok(H5Pset_attr_phase_change(group_creation.get(), kCompactAttributes, kDenseAttributes),
             "H5Pset_attr_phase_change", "group list");
  }

  void build_types() {
    string_type = h5::vlen_string_type();
    if (!string_type.valid()) fail("H5Tcopy/H5Tset_size", "variable-length string type");

    build_compound({{"id", offsetof(ObjectRow, id), H5T_NATIVE_INT32, H5T_STD_I32LE},
                    {"vertices", offsetof(ObjectRow, vertices), H5T_NATIVE_INT32, H5T_STD_I32LE},
                    {"triangles", offsetof(ObjectRow, triangles), H5T_NATIVE_INT32,
                     H5T_STD_I32LE},
                    {"is_static", offsetof(ObjectRow, is_static), H5T_NATIVE_UINT8, H5T_STD_U8LE}},
                   sizeof(ObjectRow), object_mem_type, object_file_type);

    const hsize_t three[1] = {3};
    Handle point_mem(check_id(H5Tarray_create2(H5T_NATIVE_DOUBLE, 1, three), "H5Tarray_create2",
                              "point type"),
                     H5Tclose);
    Handle point_file(check_id(H5Tarray_create2(H5T_IEEE_F64LE, 1, three), "H5Tarray_create2",
                               "point type"),
                      H5Tclose);
    build_compound(
        {{"object", offsetof(InterRow, object), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"nearest_object", offsetof(InterRow, nearest_object), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"distance", offsetof(InterRow, distance), H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE},
         {"tri_a", offsetof(InterRow, tri_a), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"tri_b", offsetof(InterRow, tri_b), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"point_a", offsetof(InterRow, point_a), point_mem.get(), point_file.get()},
         {"point_b", offsetof(InterRow, point_b), point_mem.get(), point_file.get()},
         {"case", offsetof(InterRow, kind), H5T_NATIVE_UINT8, H5T_STD_U8LE}},
        sizeof(InterRow), inter_mem_type, inter_file_type);
    build_compound(
        {{"object", offsetof(IntraRow, object), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"triangle", offsetof(IntraRow, triangle), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"nearest", offsetof(IntraRow, nearest), H5T_NATIVE_INT32, H5T_STD_I32LE},
         {"distance", offsetof(IntraRow, distance), H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE},
         {"point_a", offsetof(IntraRow, point_a), point_mem.get(), point_file.get()},
         {"point_b", offsetof(IntraRow, point_b), point_mem.get(), point_file.get()},
         {"case", offsetof(IntraRow, kind), H5T_NATIVE_UINT8, H5T_STD_U8LE}},
        sizeof(IntraRow), intra_mem_type, intra_file_type);
    build_pd_types(point_mem.get(), point_file.get());
  }

  void build_pd_types(hid_t point_mem, hid_t point_file) {
    auto i32 = [](const char* name, std::size_t offset) {
      return Member{name, offset, H5T_NATIVE_INT32, H5T_STD_I32LE};
    };
    build_compound({i32("object_a", offsetof(PairRow, object_a)), i32("tri_a", offsetof(PairRow, tri_a)),
                    i32("object_b", offsetof(PairRow, object_b)), i32("tri_b", offsetof(PairRow, tri_b))},
                   sizeof(PairRow), pair_mem_type, pair_file_type);
    build_compound({i32("object_a", offsetof(PdRow, object_a)), i32("object_b", offsetof(PdRow, object_b)),
                    {"status", offsetof(PdRow, status), H5T_NATIVE_UINT8, H5T_STD_U8LE},
                    {"depth", offsetof(PdRow, depth), H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE},
                    {"direction", offsetof(PdRow, direction), point_mem, point_file},
                    i32("deepest_object", offsetof(PdRow, deepest_object)),
                    i32("deepest_vertex", offsetof(PdRow, deepest_vertex)),
                    {"deepest_point", offsetof(PdRow, deepest_point), point_mem, point_file},
                    {"nearest_point", offsetof(PdRow, nearest_point), point_mem, point_file},
                    {"reason", offsetof(PdRow, reason), H5T_NATIVE_UINT8, H5T_STD_U8LE},
                    i32("reason_a", offsetof(PdRow, reason_a)), i32("reason_b", offsetof(PdRow, reason_b))},
                   sizeof(PdRow), pd_mem_type, pd_file_type);
    build_compound({i32("pair", offsetof(FeatureRow, pair)), i32("object", offsetof(FeatureRow, object)),
                    i32("vertex", offsetof(FeatureRow, id)),
                    {"side", offsetof(FeatureRow, side), H5T_NATIVE_UINT8, H5T_STD_U8LE}},
                   sizeof(FeatureRow), vertex_feature_mem_type, vertex_feature_file_type);
    build_compound({i32("pair", offsetof(FeatureRow, pair)), i32("object", offsetof(FeatureRow, object)),
                    i32("triangle", offsetof(FeatureRow, id)),
                    {"side", offsetof(FeatureRow, side), H5T_NATIVE_UINT8, H5T_STD_U8LE}},
                   sizeof(FeatureRow), triangle_feature_mem_type, triangle_feature_file_type);
  }

  void write_intersecting_pairs(hid_t group, const std::string& where,
                                const std::vector<IntersectingPair>& pairs) const {
    std::vector<PairRow> rows;
    rows.reserve(pairs.size());
    for (const IntersectingPair& p : pairs) rows.push_back({p.object_a, p.tri_a, p.object_b, p.tri_b});
    write_dataset(group, where, "intersecting_pairs", pair_file_type.get(), pair_mem_type.get(),
                  rows.size(), rows.data());
  }

  void write_pd(hid_t group, const std::string& where, const std::vector<PenetrationDepth>& pd) const {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    std::vector<PdRow> rows;
    std::vector<FeatureRow> vertices, triangles;
    for (std::size_t k = 0; k < pd.size(); ++k) {
      const PenetrationDepth& p = pd[k];
      const bool ok = p.status == PdStatus::Ok;
      PdRow row{};
      row.object_a = p.objects[0];
      row.object_b = p.objects[1];
      row.status = static_cast<std::uint8_t>(p.status);
      row.reason = static_cast<std::uint8_t>(p.reason);
      row.reason_a = p.reason_features[0];
      row.reason_b = p.reason_features[1];
      row.depth = ok ? p.depth : kNaN;
      row.deepest_object = ok ? p.deepest_object : kNoIndex;
      row.deepest_vertex = ok ? p.deepest_vertex : kNoIndex;
      const bool has_deepest = row.deepest_vertex != kNoIndex;
      for (int c = 0; c < 3; ++c) {
        row.direction[c] = ok ? p.direction[c] : kNaN;
        row.deepest_point[c] = has_deepest ? p.deepest_point[c] : kNaN;
        row.nearest_point[c] = has_deepest ? p.nearest_point[c] : kNaN;
      }
      rows.push_back(row);
      const auto pair = static_cast<std::int32_t>(k);
      for (std::size_t side = 0; side < 2; ++side) {
        const auto s8 = static_cast<std::uint8_t>(side);
        for (Index v : p.inside_vertices[side]) vertices.push_back({pair, p.objects[side], v, s8});
        for (Index t : p.overlapping_triangles[side]) triangles.push_back({pair, p.objects[side], t, s8});
      }
    }
    const std::string pd_where = where + "/pd";
    Handle g = create_group(group, "pd", pd_where);
    write_dataset(g.get(), pd_where, "pairs", pd_file_type.get(), pd_mem_type.get(), rows.size(), rows.data());
    write_dataset(g.get(), pd_where, "inside_vertices", vertex_feature_file_type.get(),
                  vertex_feature_mem_type.get(), vertices.size(), vertices.data());
    write_dataset(g.get(), pd_where, "overlapping_triangles", triangle_feature_file_type.get(),
                  triangle_feature_mem_type.get(), triangles.size(), triangles.data());
    close_checked(g, "H5Gclose", pd_where);
  }

  void build_ccd_types() {
    const hid_t i32 = H5T_NATIVE_INT32, i32le = H5T_STD_I32LE;
    build_compound({{"object_v", offsetof(CcdVfRow, object_v), i32, i32le},
                    {"vertex", offsetof(CcdVfRow, vertex), i32, i32le},
                    {"object_f", offsetof(CcdVfRow, object_f), i32, i32le},
                    {"face", offsetof(CcdVfRow, face), i32, i32le},
                    {"toi", offsetof(CcdVfRow, toi), H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE}},
                   sizeof(CcdVfRow), ccd_vf_mem_type, ccd_vf_file_type);
    build_compound({{"object_a", offsetof(CcdEeRow, object_a), i32, i32le},
                    {"a0", offsetof(CcdEeRow, a0), i32, i32le},
                    {"a1", offsetof(CcdEeRow, a1), i32, i32le},
                    {"object_b", offsetof(CcdEeRow, object_b), i32, i32le},
                    {"b0", offsetof(CcdEeRow, b0), i32, i32le},
                    {"b1", offsetof(CcdEeRow, b1), i32, i32le},
                    {"toi", offsetof(CcdEeRow, toi), H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE}},
                   sizeof(CcdEeRow), ccd_ee_mem_type, ccd_ee_file_type);
    build_compound({{"object_a", offsetof(CcdPairRow, object_a), i32, i32le},
                    {"object_b", offsetof(CcdPairRow, object_b), i32, i32le},
                    {"toi", offsetof(CcdPairRow, toi), H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE},
                    {"primitive_pairs", offsetof(CcdPairRow, primitive_pairs), H5T_NATIVE_UINT64,
                     H5T_STD_U64LE}},
                   sizeof(CcdPairRow), ccd_pair_mem_type, ccd_pair_file_type);
  }

  void write_attribute(hid_t owner, const std::string& owner_name, const char* name,
                       hid_t file_type, hid_t mem_type, const void* value) const {
    const std::string where = owner_name + "@" + name;
    Handle space(check_id(H5Screate(H5S_SCALAR), "H5Screate", where), H5Sclose);
    Handle attr(check_id(H5Acreate2(owner, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT),
                         "H5Acreate2", where),
                H5Aclose);
    check_ok(H5Awrite(attr.get(), mem_type, value), "H5Awrite", where);
    close_checked(attr, "H5Aclose", where);
  }
  void write_attribute(hid_t owner, const std::string& owner_name, const char* name,
                       const std::string& value) const {
    const std::string valid = valid_utf8(value);
    const char* text = valid.c_str();
    write_attribute(owner, owner_name, name, string_type.get(), string_type.get(), &text);
  }
  void write_attribute(hid_t owner, const std::string& owner_name, const char* name,
                       std::int32_t value) const {
    write_attribute(owner, owner_name, name, H5T_STD_I32LE, H5T_NATIVE_INT32, &value);
  }
  void write_attribute(hid_t owner, const std::string& owner_name, const char* name,
                       std::uint64_t value) const {
    write_attribute(owner, owner_name, name, H5T_STD_U64LE, H5T_NATIVE_UINT64, &value);
  }
  void write_attribute(hid_t owner, const std::string& owner_name, const char* name,
                       double value) const {
    write_attribute(owner, owner_name, name, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, &value);
  }
  // A 1-D array of strings (possibly empty).
  void write_attribute(hid_t owner, const std::string& owner_name, const char* name,
                       const std::vector<std::string>& values) const {
    const std::string where = owner_name + "@" + name;
    std::vector<std::string> valid;
    for (const std::string& v : values) valid.push_back(valid_utf8(v));
    std::vector<const char*> texts;
    texts.reserve(values.size());
    for (const std::string& v : valid) texts.push_back(v.c_str());
    const hsize_t n[1] = {values.size()};
    Handle space(check_id(H5Screate_simple(1, n, nullptr), "H5Screate_simple", where), H5Sclose);
    Handle attr(check_id(H5Acreate2(owner, name, string_type.get(), space.get(), H5P_DEFAULT,
                                    H5P_DEFAULT),
                         "H5Acreate2", where),
                H5Aclose);
    if (!texts.empty()) {
      check_ok(H5Awrite(attr.get(), string_type.get(), texts.data()), "H5Awrite", where);
    }
    close_checked(attr, "H5Aclose", where);
  }

  // A 1-D dataset of `rows` elements (possibly none).
  void write_dataset(hid_t parent, const std::string& parent_name, const char* name,
                     hid_t file_type, hid_t mem_type, std::size_t rows, const void* data) const {
    const std::string where = parent_name + "/" + name;
    const hsize_t n[1] = {rows};
    Handle space(check_id(H5Screate_simple(1, n, nullptr), "H5Screate_simple", where), H5Sclose);
    Handle dataset(check_id(H5Dcreate2(parent, name, file_type, space.get(), H5P_DEFAULT,
                                       H5P_DEFAULT, H5P_DEFAULT),
                            "H5Dcreate2", where),
                   H5Dclose);
    if (rows > 0) {
      // HDF5 otherwise allocates and zeroes its default 1 MiB conversion buffer on every
      // write, which dominated the time of a frame; a buffer of the data's size suffices
      // (HDF5 converts in strips when it is smaller). The floor covers elements that are
      // larger on the way to disk than H5Tget_size says (a variable-length string: 8 vs 16).
      constexpr std::size_t kMinTransferBuffer = 4096;
      const std::size_t row_bytes = std::max(H5Tget_size(mem_type), H5Tget_size(file_type));
      check_ok(H5Pset_buffer(transfer.get(), std::max(rows * row_bytes, kMinTransferBuffer),
                             nullptr, nullptr),
               "H5Pset_buffer", where);
      check_ok(H5Dwrite(dataset.get(), mem_type, H5S_ALL, H5S_ALL, transfer.get(), data),
               "H5Dwrite", where);
    }
    close_checked(dataset, "H5Dclose", where);
  }

  Handle create_group(hid_t parent, const char* name, const std::string& where) const {
    return Handle(
        check_id(H5Gcreate2(parent, name, H5P_DEFAULT, group_creation.get(), H5P_DEFAULT),
                 "H5Gcreate2", where),
        H5Gclose);
  }

  void write_objects(hid_t group, const std::string& where, const FrameResult& frame) const {
    std::vector<ObjectRow> rows;
    std::vector<std::string> valid;
    std::vector<const char*> names;
    rows.reserve(frame.objects.size());
    valid.reserve(frame.objects.size());
    names.reserve(frame.objects.size());
    for (const ObjectInfo& o : frame.objects) {
      ObjectRow row{};
      row.id = o.id;
      row.vertices = o.vertices;
      row.triangles = o.triangles;
      row.is_static = o.is_static ? 1 : 0;
      rows.push_back(row);
      valid.push_back(valid_utf8(o.name));
      names.push_back(valid.back().c_str());
    }
    write_dataset(group, where, "objects", object_file_type.get(), object_mem_type.get(),
                  rows.size(), rows.data());
    write_dataset(group, where, "object_names", string_type.get(), string_type.get(),
                  names.size(), names.data());
  }

  void write_inter(hid_t group, const std::string& where,
                   const std::vector<InterObjectDistance>& inter) const {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    std::vector<InterRow> rows;
    rows.reserve(inter.size());
    for (const InterObjectDistance& d : inter) {
      InterRow row{};
      row.object = d.object;
      if (d.has_nearest()) {
        row.nearest_object = d.nearest_object;
        row.distance = d.distance;
        row.tri_a = d.triangles[0];
        row.tri_b = d.triangles[1];
        for (int k = 0; k < 3; ++k) {
          row.point_a[k] = d.points[0][k];
          row.point_b[k] = d.points[1][k];
        }
        row.kind = case_code(d.kind);
      } else {
        row.nearest_object = kNoIndex;
        row.distance = kInfinity;
        row.tri_a = kNoIndex;
        row.tri_b = kNoIndex;
        for (int k = 0; k < 3; ++k) row.point_a[k] = row.point_b[k] = kNaN;
        row.kind = kHdf5CaseNone;
      }
      rows.push_back(row);
    }
    const std::string dist_where = where + "/distance";
    Handle distance = create_group(group, "distance", dist_where);
    write_dataset(distance.get(), dist_where, "inter", inter_file_type.get(),
                  inter_mem_type.get(), rows.size(), rows.data());
    close_checked(distance, "H5Gclose", dist_where);
  }

  // The frame's "distance" group: opened when another query's block already made it.
  Handle distance_group(hid_t group, const std::string& where) const {
    const std::string dist_where = where + "/distance";
    const htri_t exists = H5Lexists(group, "distance", H5P_DEFAULT);
    check_ok(exists < 0 ? -1 : 0, "H5Lexists", dist_where);
    if (exists == 0) return create_group(group, "distance", dist_where);
    return Handle(check_id(H5Gopen2(group, "distance", H5P_DEFAULT), "H5Gopen2", dist_where),
                  H5Gclose);
  }

  // distance/intra: every triangle of every object (object-major, triangle order) with its
  // nearest non-adjacent triangle; distance/intra_min: one row per object, its minimum
  // (triangle and nearest are the pair). No such triangle: nearest -1, distance +inf, points
  // NaN, case 255.
  void write_intra(hid_t group, const std::string& where,
                   const std::vector<IntraObjectDistance>& intra) const {
    constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
    auto row_of = [&](Index object, Index triangle, Index nearest, double distance,
                      const std::array<Vec3, 2>& points, TriangleDistanceCase kind) {
      IntraRow row{};
      row.object = object;
      row.triangle = triangle;
      row.nearest = nearest;
      const bool none = nearest == kNoIndex;
      row.distance = none ? kInfinity : distance;
      for (int k = 0; k < 3; ++k) {
        row.point_a[k] = none ? kNaN : points[0][k];
        row.point_b[k] = none ? kNaN : points[1][k];
      }
      row.kind = none ? kHdf5CaseNone : case_code(kind);
      return row;
    };
    std::vector<IntraRow> rows, mins;
    for (const IntraObjectDistance& d : intra) {
      for (size_t t = 0; t < d.per_triangle.size(); ++t) {
        const IntraTriangleNearest& n = d.per_triangle[t];
        rows.push_back(row_of(d.object, static_cast<Index>(t), n.nearest, n.distance, n.points, n.kind));
      }
      const TriangleDistanceCase kind =
          d.has_pair() ? d.per_triangle[static_cast<size_t>(d.triangles[0])].kind
                       : TriangleDistanceCase::Intersecting;
      mins.push_back(row_of(d.object, d.triangles[0], d.triangles[1], d.distance, d.points, kind));
    }
    const std::string dist_where = where + "/distance";
    Handle distance = distance_group(group, where);
    write_dataset(distance.get(), dist_where, "intra", intra_file_type.get(),
                  intra_mem_type.get(), rows.size(), rows.data());
    write_dataset(distance.get(), dist_where, "intra_min", intra_file_type.get(),
                  intra_mem_type.get(), mins.size(), mins.data());
    close_checked(distance, "H5Gclose", dist_where);
  }

  // Group ccd/ of a frame: vf, ee, pairs, skipped_objects + skipped_reasons; attributes
  // to_frame and the counters and times of the step.
  void write_ccd(hid_t group, const std::string& where, const CcdStepResult& c) const {
    const std::string ccd_where = where + "/ccd";
    Handle ccd = create_group(group, "ccd", ccd_where);
    const hid_t g = ccd.get();
    std::vector<CcdVfRow> vf;
    vf.reserve(c.vf.size());
    for (const CcdVertexFace& h : c.vf) vf.push_back({h.object_v, h.vertex, h.object_f, h.face, h.toi});
    write_dataset(g, ccd_where, "vf", ccd_vf_file_type.get(), ccd_vf_mem_type.get(), vf.size(), vf.data());
    std::vector<CcdEeRow> ee;
    ee.reserve(c.ee.size());
    for (const CcdEdgeEdge& h : c.ee)
      ee.push_back({h.object_a, h.edge_a[0], h.edge_a[1], h.object_b, h.edge_b[0], h.edge_b[1], h.toi});
    write_dataset(g, ccd_where, "ee", ccd_ee_file_type.get(), ccd_ee_mem_type.get(), ee.size(), ee.data());
    std::vector<CcdPairRow> pairs;
    pairs.reserve(c.pairs.size());
    for (const CcdObjectPair& p : c.pairs)
      pairs.push_back({p.objects[0], p.objects[1], p.toi, p.primitive_pairs});
    write_dataset(g, ccd_where, "pairs", ccd_pair_file_type.get(), ccd_pair_mem_type.get(),
                  pairs.size(), pairs.data());
    std::vector<std::int32_t> skipped;
    std::vector<std::string> valid;
    std::vector<const char*> reasons;
    valid.reserve(c.skipped.size());
    for (const CcdSkipped& s : c.skipped) {
      skipped.push_back(s.object);
      valid.push_back(valid_utf8(s.reason));
      reasons.push_back(valid.back().c_str());
    }
    write_dataset(g, ccd_where, "skipped_objects", H5T_STD_I32LE, H5T_NATIVE_INT32, skipped.size(),
                  skipped.data());
    write_dataset(g, ccd_where, "skipped_reasons", string_type.get(), string_type.get(),
                  reasons.size(), reasons.data());
    const CcdCounters& k = c.counters;
    write_attribute(g, ccd_where, "to_frame", std::int32_t{c.to_frame});
    write_attribute(g, ccd_where, "elementary_tests", std::uint64_t{k.elementary_tests()});
    write_attribute(g, ccd_where, "vf_tests", std::uint64_t{k.vf_tests});
    write_attribute(g, ccd_where, "ee_tests", std::uint64_t{k.ee_tests});
    write_attribute(g, ccd_where, "object_pairs", std::uint64_t{k.object_pairs});
    write_attribute(g, ccd_where, "triangle_pairs", std::uint64_t{k.triangle_pairs});
    write_attribute(g, ccd_where, "separated_pairs", std::uint64_t{k.separated_pairs});
    write_attribute(g, ccd_where, "unshared_pairs", std::uint64_t{k.unshared_pairs});
    write_attribute(g, ccd_where, "separated_primitives", std::uint64_t{k.separated_primitives});
    write_attribute(g, ccd_where, "culled_triangles", std::uint64_t{k.culled_triangles});
    write_attribute(g, ccd_where, "limit_hits", std::uint64_t{k.limit_hits});
    write_attribute(g, ccd_where, "time_ms_aabb", c.aabb_ms);
    write_attribute(g, ccd_where, "time_ms_voronoi", c.voronoi_ms);
    write_attribute(g, ccd_where, "time_ms_exact", c.exact_ms);
    if (c.voxel_grid) {
      write_attribute(g, ccd_where, "voronoi_grid_x", (*c.voxel_grid)[0]);
      write_attribute(g, ccd_where, "voronoi_grid_y", (*c.voxel_grid)[1]);
      write_attribute(g, ccd_where, "voronoi_grid_z", (*c.voxel_grid)[2]);
      write_attribute(g, ccd_where, "voronoi_cell", c.voxel_cell);
    }
    if (c.stage2) write_attribute(g, ccd_where, "voxelized_triangles", std::uint64_t{k.voxelized_triangles});
    close_checked(ccd, "H5Gclose", ccd_where);
  }

  void write_stats(hid_t group, const std::string& where, const FrameResult& frame,
                   double write_ms) const {
    const std::string stats_where = where + "/stats";
    Handle stats = create_group(group, "stats", stats_where);
    const hid_t s = stats.get();
    const StageTimes& t = frame.time_ms;
    write_attribute(s, stats_where, "time_ms_load", t.load);
    write_attribute(s, stats_where, "time_ms_aabb", t.aabb);
    write_attribute(s, stats_where, "time_ms_voronoi", t.voronoi);
    write_attribute(s, stats_where, "time_ms_exact", t.exact);
    write_attribute(s, stats_where, "time_ms_write", write_ms);
    write_attribute(s, stats_where, "time_ms_total", t.total);
    write_attribute(s, stats_where, "exact_tests", std::uint64_t{frame.counters.exact_tests});
    write_attribute(s, stats_where, "pns_pairs", std::uint64_t{frame.counters.object_pns_pairs});
    write_attribute(s, stats_where, "feature_pns",
                    std::uint64_t{frame.counters.feature_pns});
    write_attribute(s, stats_where, "separation_culled",
                    std::uint64_t{frame.counters.separation_culled});
    if (frame.intersecting_pairs)
      write_attribute(s, stats_where, "intersection_tests", std::uint64_t{frame.intersection_tests});
    if (frame.voronoi) {
      const VoronoiFrameStats& v = *frame.voronoi;
      for (int k = 0; k < 3; ++k) {
        const std::string name = std::string("voronoi_grid_") + "xyz"[k];
        write_attribute(s, stats_where, name.c_str(), std::int32_t{v.grid_dims[static_cast<size_t>(k)]});
      }
      write_attribute(s, stats_where, "voronoi_cell", v.cell);
      write_attribute(s, stats_where, "voronoi_delta", v.delta);
      write_attribute(s, stats_where, "voronoi_delta_precision", v.delta_precision);
      write_attribute(s, stats_where, "voronoi_sample_voxels", std::uint64_t{v.sample_voxels});
      write_attribute(s, stats_where, "voronoi_sampled_triangles", v.sampled_triangles.value_or(0));
      write_attribute(s, stats_where, "voronoi_backend_triangles", std::uint64_t{v.backend_triangles});
      write_attribute(s, stats_where, "voronoi_time_ms_upload", v.upload_ms);
      write_attribute(s, stats_where, "voronoi_time_ms_compute", v.compute_ms);
      write_attribute(s, stats_where, "voronoi_time_ms_readback", v.readback_ms);
    }
    if (frame.intra) {
      write_attribute(s, stats_where, "intra_exact_tests", std::uint64_t{frame.counters.intra_exact_tests});
      write_attribute(s, stats_where, "intra_candidates", std::uint64_t{frame.counters.intra_candidates});
      write_attribute(s, stats_where, "intra_voronoi_culled", std::uint64_t{frame.counters.intra_voronoi_culled});
      write_attribute(s, stats_where, "intra_separation_culled", std::uint64_t{frame.counters.intra_separation_culled});
      write_attribute(s, stats_where, "intra_reused", std::uint64_t{frame.counters.intra_reused});
    }
    if (frame.self_voronoi) {
      const VoronoiFrameStats& v = *frame.self_voronoi;
      for (int k = 0; k < 3; ++k) {
        const std::string name = std::string("self_voronoi_grid_") + "xyz"[k];
        write_attribute(s, stats_where, name.c_str(), std::int32_t{v.grid_dims[static_cast<size_t>(k)]});
      }
      write_attribute(s, stats_where, "self_voronoi_cell", v.cell);
      write_attribute(s, stats_where, "self_voronoi_delta", v.delta);
      write_attribute(s, stats_where, "self_voronoi_samples", std::uint64_t{v.samples});
      write_attribute(s, stats_where, "self_voronoi_sampled_triangles", v.sampled_triangles.value_or(0));
      write_attribute(s, stats_where, "self_voronoi_backend_triangles", std::uint64_t{v.backend_triangles});
      write_attribute(s, stats_where, "self_voronoi_time_ms_compute", v.compute_ms);
    }
    close_checked(stats, "H5Gclose", stats_where);
  }
};

Hdf5ResultWriter::Hdf5ResultWriter(const std::filesystem::path& file, const RunInfo& info)
    : impl_(std::make_unique<Impl>()) {
  h5::QuietErrors quiet;
  Impl& m = *impl_;
  m.path = file.string();
  m.build_types();
  m.build_ccd_types();
  m.build_property_lists();
  // The HDF5 1.8 file format (read by every HDF5 since 1.8, h5py and h5dump included): a
  // small group keeps its links in its object header instead of a B-tree and heap of its
  // own, which makes the per-frame groups about a third smaller on disk.
  m.file_access = Handle(m.check_id(H5Pcreate(H5P_FILE_ACCESS), "H5Pcreate", ""), H5Pclose);
  m.check_ok(H5Pset_libver_bounds(m.file_access.get(), H5F_LIBVER_V18, H5F_LIBVER_V18),
             "H5Pset_libver_bounds", "");
  m.file = Handle(
      m.check_id(H5Fcreate(m.path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, m.file_access.get()),
                 "H5Fcreate", ""),
      H5Fclose);
  const hid_t root = m.file.get();
  m.write_attribute(root, "/", "tool", std::string("vproxq"));
  m.write_attribute(root, "/", "version", info.tool_version);
  m.write_attribute(root, "/", "format_version", std::int32_t{kFormatVersion});
  m.write_attribute(root, "/", "scene", info.scene_name);
  m.write_attribute(root, "/", "scene_path", info.scene);
  m.write_attribute(root, "/", "queries", join(info.queries, ","));
  m.write_attribute(root, "/", "voronoi", info.voronoi);
  m.write_attribute(root, "/", "grid", std::int32_t{info.grid});
  m.write_attribute(root, "/", "device", info.device);
  m.write_attribute(root, "/", "threads", std::int32_t{info.threads});
  m.write_attribute(root, "/", "self", std::int32_t{info.self ? 1 : 0});
  m.frames = m.create_group(root, "frames", "/frames");
}

double Hdf5ResultWriter::write_frame(const FrameResult& frame,
                                     std::chrono::steady_clock::time_point started) {
  h5::QuietErrors quiet;
  Impl& m = *impl_;
  if (!m.frames.valid()) throw RuntimeError("HDF5: '" + m.path + "' is already closed");
  if (m.frames_since_open == Impl::kFramesPerOpen) m.reopen();
  ++m.frames_since_open;
  const std::string name = frame_group_name(frame.frame);
  const std::string where = "/frames/" + name;
  Handle group = m.create_group(m.frames.get(), name.c_str(), where);
  m.write_attribute(group.get(), where, "frame", std::int32_t{frame.frame});
  m.write_attribute(group.get(), where, "files", frame.files);
  m.write_objects(group.get(), where, frame);
  if (frame.inter) m.write_inter(group.get(), where, *frame.inter);
  if (frame.intersecting_pairs) m.write_intersecting_pairs(group.get(), where, *frame.intersecting_pairs);
  if (frame.pd) m.write_pd(group.get(), where, *frame.pd);
  if (frame.intra) m.write_intra(group.get(), where, *frame.intra);
  if (frame.ccd) m.write_ccd(group.get(), where, *frame.ccd);

  const double write_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started)
          .count();
  m.write_stats(group.get(), where, frame, write_ms);
  m.close_checked(group, "H5Gclose", where);
  return write_ms;
}

void Hdf5ResultWriter::close() {
  h5::QuietErrors quiet;
  Impl& m = *impl_;
  m.close_checked(m.frames, "H5Gclose", "/frames");
  m.close_checked(m.file, "H5Fclose", "");
}

Hdf5ResultWriter::~Hdf5ResultWriter() {
  if (!impl_) return;
  h5::QuietErrors quiet;
  impl_->frames.close();
  impl_->file.close();
}

}  // namespace vproxq::detail
