#include "io/json_writer.hpp"

#include "core/errors.hpp"
#include "io/output.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>

#include <unistd.h>

namespace vproxq {

std::string valid_utf8(const std::string& text) {
  const std::string quoted =
      nlohmann::json(text).dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return nlohmann::json::parse(quoted).get<std::string>();
}

}  // namespace vproxq

namespace vproxq::detail {

namespace {

using Json = nlohmann::ordered_json;

Json point_json(const Vec3& p) { return Json::array({p.x(), p.y(), p.z()}); }

/// The distance, triangle pair and closest points of an answer, or nulls where there is none
/// (key order as in DESIGN.md).
void put_pair(Json& r, bool has, double distance, const std::array<Index, 2>& triangles,
              const std::array<Vec3, 2>& points) {
  r["distance"] = has ? Json(distance) : Json(nullptr);
  r["triangles"] = has ? Json::array({triangles[0], triangles[1]}) : Json(nullptr);
  r["points"] = has ? Json::array({point_json(points[0]), point_json(points[1])}) : Json(nullptr);
}

Json inter_json(const InterObjectDistance& d) {
  Json r;
  r["object"] = d.object;
  r["nearest_object"] = d.has_nearest() ? Json(d.nearest_object) : Json(nullptr);
  put_pair(r, d.has_nearest(), d.distance, d.triangles, d.points);
  return r;
}

Json pd_json(const PenetrationDepth& p) {
  Json r;
  r["objects"] = Json::array({p.objects[0], p.objects[1]});
  if (p.status == PdStatus::Ok) {
    r["depth"] = p.depth;
    r["direction"] = point_json(p.direction);
  } else {
    r["depth"] = nullptr;
    r["direction"] = nullptr;
    r["status"] = pd_status_name(p.status);
    if (p.reason != PdReason::None) r["reason"] = pd_reason_name(p.reason);
  }
  return r;
}

Json intra_json(const IntraObjectDistance& d) {
  Json r;
  r["object"] = d.object;
  // No pair: no two triangles of the object are non-adjacent.
  put_pair(r, d.has_pair(), d.distance, d.triangles, d.points);
  return r;
}

/// A Stage II block of the frame's stats; `samples` (voxel-triangle samples) only for the self
/// Stage II, whose samples are per triangle (the inter-object one samples each voxel once).
Json voronoi_stats_json(const VoronoiFrameStats& v, bool samples) {
  Json vj;
  vj["grid"] = {v.grid_dims[0], v.grid_dims[1], v.grid_dims[2]};
  vj["cell"] = v.cell;
  vj["delta"] = v.delta;
  vj["delta_precision"] = v.delta_precision;
  vj["sample_voxels"] = v.sample_voxels;
  if (samples) vj["samples"] = v.samples;
  if (v.sampled_triangles) vj["sampled_triangles"] = *v.sampled_triangles;
  vj["backend_triangles"] = v.backend_triangles;
  vj["time_ms"] = {{"setup", v.setup_ms}, {"upload", v.upload_ms}, {"compute", v.compute_ms},
                   {"readback", v.readback_ms}, {"scan", v.scan_ms}};
  return vj;
}

Json ccd_json(const CcdStepResult& c) {
  Json r;
  r["to_frame"] = c.to_frame;
  Json skipped = Json::array();
  for (const CcdSkipped& s : c.skipped) skipped.push_back({{"object", s.object}, {"reason", s.reason}});
  r["skipped"] = std::move(skipped);
  Json pairs = Json::array();
  for (const CcdObjectPair& p : c.pairs)
    pairs.push_back({{"objects", {p.objects[0], p.objects[1]}}, {"toi", p.toi},
                     {"primitive_pairs", p.primitive_pairs}});
  r["pairs"] = std::move(pairs);
  return r;
}

Json ccd_stats_json(const CcdStepResult& c) {
  const CcdCounters& k = c.counters;
  Json r;
  r["elementary_tests"] = k.elementary_tests();
  r["vf_tests"] = k.vf_tests;
  r["ee_tests"] = k.ee_tests;
  r["object_pairs"] = k.object_pairs;
  r["triangle_pairs"] = k.triangle_pairs;
  r["separated_pairs"] = k.separated_pairs;
  r["unshared_pairs"] = k.unshared_pairs;
  r["separated_primitives"] = k.separated_primitives;
  r["culled_triangles"] = k.culled_triangles;
  if (c.stage2) r["voxelized_triangles"] = k.voxelized_triangles;
  r["limit_hits"] = k.limit_hits;
  r["vf_pairs"] = c.vf.size();
  r["ee_pairs"] = c.ee.size();
  if (c.voxel_grid) {
    r["grid"] = {(*c.voxel_grid)[0], (*c.voxel_grid)[1], (*c.voxel_grid)[2]};
    r["cell"] = c.voxel_cell;
  }
  r["time_ms"] = {{"aabb", c.aabb_ms}, {"voronoi", c.voronoi_ms}, {"exact", c.exact_ms}};
  return r;
}

// True when format_json spreads `value` over several lines.
bool spreads(const Json& value) {
  if (value.is_array()) {
    return std::any_of(value.begin(), value.end(), [](const Json& e) { return e.is_object(); });
  }
  if (value.is_object()) {
    return std::any_of(value.begin(), value.end(), [](const Json& e) { return spreads(e); });
  }
  return false;
}

std::string compact(const Json& value) {
  return value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// `spread` forces the top level of `value` onto several lines (used for each frame).
void format_into(std::string& out, const Json& value, int indent, bool spread = false) {
  if (!spread && !spreads(value)) {
    out += compact(value);
    return;
  }
  const std::string inner(static_cast<std::size_t>(indent + 1), ' ');
  const bool object = value.is_object();
  out += object ? "{\n" : "[\n";
  bool first = true;
  for (auto it = value.begin(); it != value.end(); ++it) {
    if (!first) out += ",\n";
    first = false;
    out += inner;
    if (object) {
      out += compact(Json(it.key()));
      out += ": ";
    }
    format_into(out, it.value(), indent + 1);
  }
  out += '\n';
  out += std::string(static_cast<std::size_t>(indent), ' ');
  out += object ? '}' : ']';
}

}  // namespace

Json run_header_json(const RunInfo& info) {
  Json j;
  j["tool"] = "vproxq";
  j["version"] = info.tool_version;
  j["format_version"] = kFormatVersion;
  j["scene"] = info.scene_name;
  j["queries"] = info.queries;
  Json settings;
  settings["voronoi"] = info.voronoi;
  settings["grid"] = info.grid == 0 ? Json(nullptr) : Json(info.grid);
  settings["device"] = info.device.empty() ? Json(nullptr) : Json(info.device);
  settings["threads"] = info.threads;
  settings["self"] = info.self;
  j["settings"] = std::move(settings);
  return j;
}

Json frame_json(const FrameResult& frame, double write_ms) {
  Json j;
  j["frame"] = frame.frame;
  Json objects = Json::array();
  for (const ObjectInfo& o : frame.objects) {
    Json r;
    r["id"] = o.id;
    r["name"] = o.name;
    r["vertices"] = o.vertices;
    r["triangles"] = o.triangles;
    if (o.is_static) r["static"] = true;
    objects.push_back(std::move(r));
  }
  j["objects"] = std::move(objects);
  // Key order as in DESIGN.md: distance {inter, intra, intersecting_pairs}, ccd, pd, stats.
  if (frame.inter) {
    Json inter = Json::array();
    for (const InterObjectDistance& d : *frame.inter) inter.push_back(inter_json(d));
    j["distance"]["inter"] = std::move(inter);
  }
  if (frame.intra) {
    Json intra = Json::array();
    for (const IntraObjectDistance& d : *frame.intra) intra.push_back(intra_json(d));
    j["distance"]["intra"] = std::move(intra);
  }
  if (frame.inter && frame.intersecting_pairs)
    j["distance"]["intersecting_pairs"] = frame.intersecting_pairs->size();
  if (frame.ccd) j["ccd"] = ccd_json(*frame.ccd);
  if (frame.pd) {
    Json pd = Json::array();
    for (const PenetrationDepth& p : *frame.pd) pd.push_back(pd_json(p));
    j["pd"] = std::move(pd);
  }
  const StageTimes& t = frame.time_ms;
  Json time_ms;
  time_ms["load"] = t.load;
  time_ms["aabb"] = t.aabb;
  time_ms["voronoi"] = t.voronoi;
  time_ms["exact"] = t.exact;
  time_ms["write"] = write_ms;
  time_ms["total"] = t.total;
  if (frame.intra) {
    time_ms["intra_bounds"] = t.intra_bounds;
    time_ms["intra_voronoi"] = t.intra_voronoi;
    time_ms["intra_exact"] = t.intra_exact;
  }
  Json stats;
  stats["time_ms"] = std::move(time_ms);
  stats["exact_tests"] = frame.counters.exact_tests;
  stats["pns_pairs"] = frame.counters.object_pns_pairs;
  stats["feature_pns"] = frame.counters.feature_pns;
  stats["separation_culled"] = frame.counters.separation_culled;
  if (frame.intersecting_pairs) stats["intersection_tests"] = frame.intersection_tests;
  if (frame.intra) {
    stats["intra_exact_tests"] = frame.counters.intra_exact_tests;
    stats["intra_candidates"] = frame.counters.intra_candidates;
    stats["intra_voronoi_culled"] = frame.counters.intra_voronoi_culled;
    stats["intra_separation_culled"] = frame.counters.intra_separation_culled;
    stats["intra_reused"] = frame.counters.intra_reused;
  }
  if (frame.voronoi) stats["voronoi"] = voronoi_stats_json(*frame.voronoi, false);
  if (frame.self_voronoi) stats["self_voronoi"] = voronoi_stats_json(*frame.self_voronoi, true);
  if (frame.ccd) stats["ccd"] = ccd_stats_json(*frame.ccd);
  j["stats"] = std::move(stats);
  return j;
}

std::string format_json(const Json& value, int indent) {
  std::string out;
  format_into(out, value, indent);
  return out;
}

JsonResultStream::JsonResultStream(const std::filesystem::path& file, const RunInfo& info)
    : path_(file) {
  file_.reset(std::fopen(path_.c_str(), "wb"));
  if (!file_) fail("cannot create", errno);
  std::string header = "{\n";
  const Json head = run_header_json(info);
  for (auto it = head.begin(); it != head.end(); ++it) {
    header += ' ';
    header += compact(Json(it.key()));
    header += ": ";
    format_into(header, it.value(), 1);
    header += ",\n";
  }
  header += " \"frames\": [";
  put(header);
}

void JsonResultStream::write_frame(const FrameResult& frame, double write_ms) {
  std::string text = frames_written_ == 0 ? "\n  " : ",\n  ";
  format_into(text, frame_json(frame, write_ms), 2, /*spread=*/true);
  put(text);
  ++frames_written_;
}

void JsonResultStream::close() {
  put(frames_written_ == 0 ? "]\n}\n" : "\n ]\n}\n");
  if (std::fflush(file_.get()) != 0) fail("cannot write", errno);
  if (::fsync(::fileno(file_.get())) != 0) fail("cannot sync", errno);
  if (std::fclose(file_.release()) != 0) fail("cannot close", errno);
}

JsonResultStream::~JsonResultStream() = default;

void JsonResultStream::put(const std::string& text) {
  if (!file_) throw RuntimeError("'" + path_.string() + "' is already closed");
  if (std::fwrite(text.data(), 1, text.size(), file_.get()) != text.size()) {
    fail("cannot write", errno);
  }
}

void JsonResultStream::fail(const char* what, int error) const {
  throw RuntimeError(std::string(what) + " '" + path_.string() + "': " + std::strerror(error));
}

}  // namespace vproxq::detail
