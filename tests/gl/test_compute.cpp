// GL compute helpers and the point–segment smoke shader against a CPU double reference.
#include "gl/compute.hpp"
#include "gl/point_segment_distance.hpp"
#include "gl_test_support.hpp"

#include "core/types.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace vproxq::gl {
namespace {

// Test data lies in [-1, 1]^3, so every point-to-segment vector is at most kDiameter long.
constexpr double kCoordinateBound = 1.0;
const double kDiameter = 2.0 * std::sqrt(3.0) * kCoordinateBound;
// Float32 tolerance of the shader's distances. Its evaluation is about a dozen dependent
// roundings (differences, two dot products, a division, clamp, multiply-subtract, a dot,
// sqrt), each perturbing the result by at most a few u·kDiameter, u = FLT_EPSILON/2: an error
// δt in the segment parameter moves the closest point by δt·|ab| <= ~4u·|ap|, and the distance
// is 1-Lipschitz in that point. 128·u·kDiameter (~2.6e-5) is a wide margin over that and over
// GLSL's 2.5 ULP division and sqrt. The CPU reference evaluates the same float inputs in double.
const double kDistanceTolerance = 128.0 * (FLT_EPSILON / 2.0) * kDiameter;

struct Scene {
  std::vector<float> points;    // xyz per point
  std::vector<float> segments;  // ab per segment
};

/// Random points and segments in [-1, 1]^3 with the awkward cases mixed in: degenerate
/// segments (a == b), points exactly on a segment, and an exact duplicate segment (a tie).
Scene random_scene(std::size_t point_count, std::size_t segment_count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coordinate(-kCoordinateBound, kCoordinateBound);
  Scene scene;
  for (std::size_t j = 0; j < segment_count; ++j) {
    float s[6];
    for (float& c : s) c = coordinate(rng);
    if (j % 17 == 3) std::copy(s, s + 3, s + 3);  // degenerate
    scene.segments.insert(scene.segments.end(), s, s + 6);
  }
  if (segment_count > 10) {  // the last segment duplicates segment 5
    std::copy(scene.segments.begin() + 30, scene.segments.begin() + 36,
              scene.segments.end() - 6);
  }
  for (std::size_t i = 0; i < point_count; ++i) {
    if (i % 13 == 7 && segment_count > 0) {  // a point on a segment (its float midpoint)
      const std::size_t j = (i * 7) % segment_count;
      for (int k = 0; k < 3; ++k) {
        scene.points.push_back(0.5f * (scene.segments[6 * j + k] + scene.segments[6 * j + 3 + k]));
      }
    } else {
      for (int k = 0; k < 3; ++k) scene.points.push_back(coordinate(rng));
    }
  }
  return scene;
}

/// Distance from p to the closed segment [a, b] in double; a degenerate segment is its point a.
double point_segment_distance_reference(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const Vec3 ap = p - a;
  const double length_squared = ab.squaredNorm();
  const double t = length_squared > 0 ? std::clamp(ap.dot(ab) / length_squared, 0.0, 1.0) : 0.0;
  return (ap - t * ab).norm();
}

Vec3 point_of(const std::vector<float>& xyz, std::size_t i, std::size_t stride, std::size_t at) {
  return Vec3(xyz[stride * i + at], xyz[stride * i + at + 1], xyz[stride * i + at + 2]);
}

double reference_distance(const Scene& scene, std::size_t point, std::size_t segment) {
  return point_segment_distance_reference(point_of(scene.points, point, 3, 0),
                                          point_of(scene.segments, segment, 6, 0),
                                          point_of(scene.segments, segment, 6, 3));
}

/// Checks the GPU answer of `point` against brute force in double: the distance within
/// kDistanceTolerance, and the segment either the reference's (smallest index on ties) or
/// one whose exact distance is within float error of the minimum. Returns |error|.
double check_point(const Scene& scene, const NearestSegmentsResult& gpu, std::size_t point) {
  const std::size_t segment_count = scene.segments.size() / 6;
  double best = kInfinity;
  std::size_t best_index = 0;
  for (std::size_t j = 0; j < segment_count; ++j) {
    const double d = reference_distance(scene, point, j);
    if (d < best) {
      best = d;
      best_index = j;
    }
  }
  const double error = std::abs(static_cast<double>(gpu.distance[point]) - best);
  EXPECT_LE(error, kDistanceTolerance) << "point " << point;
  const std::uint32_t index = gpu.index[point];
  EXPECT_LT(index, segment_count) << "point " << point;
  if (index != best_index && index < segment_count) {
    EXPECT_LE(reference_distance(scene, point, index) - best, 2 * kDistanceTolerance)
        << "point " << point << ": GPU chose segment " << index << ", reference " << best_index;
  }
  return error;
}

TEST(GlCompute, PointSegmentShaderMatchesCpuReference) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  // 2011 points: not a multiple of the work group size, so the bounds check is exercised.
  const Scene scene = random_scene(2011, 300, 12345);
  const NearestSegmentsResult gpu = nearest_segments_gpu(context, scene.points, scene.segments);
  ASSERT_EQ(gpu.index.size(), 2011u);
  ASSERT_EQ(gpu.distance.size(), 2011u);
  double max_error = 0;
  for (std::size_t i = 0; i < gpu.index.size(); ++i) {
    max_error = std::max(max_error, check_point(scene, gpu, i));
    EXPECT_NE(gpu.index[i], 299u) << "tie with segment 5 must go to the smaller index";
  }
  std::cout << "max |GPU - CPU double| distance error: " << max_error << " (tolerance "
            << kDistanceTolerance << ")\n";
}

TEST(GlCompute, BatchedDispatchesCoverEveryPoint) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const Scene scene = random_scene(1000, 40, 777);
  NearestSegmentsOptions options;
  options.local_size = 32;
  options.max_groups_per_dispatch = 3;  // 96 points per dispatch: 11 dispatches
  const NearestSegmentsResult gpu =
      nearest_segments_gpu(context, scene.points, scene.segments, options);
  for (std::size_t i = 0; i < gpu.index.size(); ++i) check_point(scene, gpu, i);
}

TEST(GlCompute, EmptyInputs) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const NearestSegmentsResult no_points = nearest_segments_gpu(context, {}, {0, 0, 0, 1, 1, 1});
  EXPECT_TRUE(no_points.index.empty());
  const NearestSegmentsResult no_segments =
      nearest_segments_gpu(context, {0, 0, 0, 1, 2, 3}, {});
  ASSERT_EQ(no_segments.index.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(no_segments.index[i], NearestSegmentsResult::kNoSegment);
    EXPECT_TRUE(std::isinf(no_segments.distance[i]));
  }
  EXPECT_THROW(nearest_segments_gpu(context, {0, 0}, {}), std::invalid_argument);
  EXPECT_THROW(nearest_segments_gpu(context, {}, {0, 0, 0}), std::invalid_argument);
}

TEST(GlCompute, SmokeShaderTimings) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  constexpr std::size_t kPoints = 100000;
  constexpr std::size_t kSegments = 1000;
  const Scene scene = random_scene(kPoints, kSegments, 2024);
  const NearestSegmentsResult gpu = nearest_segments_gpu(context, scene.points, scene.segments);
  for (std::size_t i = 0; i < kPoints; i += 97) check_point(scene, gpu, i);
  const GpuTimings& t = gpu.timings;
  std::cout << kPoints << " points x " << kSegments << " segments on " << context.renderer()
            << "\n  compile " << gpu.compile_ms << " ms, upload " << t.upload_ms
            << " ms, compute " << t.compute_ms << " ms (GL_TIME_ELAPSED " << t.gpu_compute_ms
            << " ms), readback " << t.readback_ms << " ms\n";
  RecordProperty("upload_ms", std::to_string(t.upload_ms));
  RecordProperty("compute_ms", std::to_string(t.compute_ms));
  RecordProperty("readback_ms", std::to_string(t.readback_ms));
  EXPECT_GE(t.upload_ms, 0);
  EXPECT_GT(t.compute_ms, 0);
  EXPECT_GE(t.readback_ms, 0);
}

TEST(GlCompute, InvalidShaderReportsTheCompileLog) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  // The error is on line 3 of the body; "#line 1" keeps the log's line numbers those of the body.
  const std::string body =
      "layout(local_size_x = 1) in;\n"
      "void main() {\n"
      "  float x = vproxq_undeclared_identifier;\n"
      "}\n";
  try {
    ComputeProgram program(context, "broken_test_shader", compose_shader_source(body));
    FAIL() << "an invalid shader compiled";
  } catch (const ShaderError& e) {
    const std::string message = e.what();
    std::cout << "expected failure: " << message << "\n";
    EXPECT_NE(message.find("broken_test_shader"), std::string::npos) << message;
    EXPECT_NE(message.find("failed to compile"), std::string::npos) << message;
    // The driver's log names the offending identifier and its line.
    EXPECT_NE(message.find("vproxq_undeclared_identifier"), std::string::npos) << message;
    const bool names_line_3 = message.find(":3(") != std::string::npos ||  // Mesa: 0:3(12)
                              message.find("(3)") != std::string::npos;    // NVIDIA: 0(3)
    EXPECT_TRUE(names_line_3) << message;
  }
}

TEST(GlCompute, LinkErrorReportsTheLinkLog) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  // Compiles, but a compute program without main() does not link.
  const std::string body = "layout(local_size_x = 1) in;\nvoid helper() {}\n";
  try {
    ComputeProgram program(context, "no_main", compose_shader_source(body));
    FAIL() << "a program without main() linked";
  } catch (const ShaderError& e) {
    const std::string message = e.what();
    std::cout << "expected failure: " << message << "\n";
    EXPECT_NE(message.find("no_main"), std::string::npos) << message;
    EXPECT_NE(message.find("failed to link"), std::string::npos) << message;
    EXPECT_NE(message.find("main"), std::string::npos) << message;
  }
}

TEST(GlCompute, ProgramReportsLocalSizeAndUniforms) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const ComputeProgram program =
      ComputeProgram::from_embedded(context, "point_segment_distance", {{"LOCAL_SIZE", "16"}});
  EXPECT_EQ(program.local_size()[0], 16u);
  EXPECT_EQ(program.local_size()[1], 1u);
  EXPECT_GE(program.uniform_location("point_count"), 0);
  EXPECT_NO_THROW(program.set_uint("segment_count", 3));
  try {
    program.uniform_location("no_such_uniform");
    ADD_FAILURE() << "no exception";
  } catch (const GlError& e) {
    EXPECT_NE(std::string(e.what()).find("no_such_uniform"), std::string::npos) << e.what();
  }
}

TEST(GlCompute, StorageBufferRoundTripAndBounds) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  std::vector<std::uint32_t> values(1000);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = static_cast<std::uint32_t>(i * i);
  StorageBuffer buffer = StorageBuffer::from_vector(context, values);
  EXPECT_EQ(buffer.size(), values.size() * sizeof(std::uint32_t));
  EXPECT_EQ(buffer.download_vector<std::uint32_t>(values.size()), values);
  EXPECT_EQ(buffer.download_vector<std::uint32_t>(2, 10), (std::vector<std::uint32_t>{100, 121}));
  const std::uint32_t patch[2] = {7, 8};
  buffer.upload(patch, sizeof patch, 4 * sizeof(std::uint32_t));
  EXPECT_EQ(buffer.download_vector<std::uint32_t>(3, 3), (std::vector<std::uint32_t>{9, 7, 8}));
  buffer.clear_to_zero(12);  // the first 3 words only
  EXPECT_EQ(buffer.download_vector<std::uint32_t>(4), (std::vector<std::uint32_t>{0, 0, 0, 9}));
  buffer.clear_to_zero(13);  // and one byte of the fourth
  EXPECT_EQ(buffer.download_vector<std::uint32_t>(2, 3), (std::vector<std::uint32_t>{0, 7}));
  EXPECT_THROW(buffer.clear_to_zero(buffer.size() + 1), std::out_of_range);
  buffer.clear_to_zero();
  EXPECT_EQ(buffer.download_vector<std::uint32_t>(values.size()),
            std::vector<std::uint32_t>(values.size(), 0));
  std::uint32_t sink[2];
  EXPECT_THROW(buffer.download(sink, sizeof sink, buffer.size() - 4), std::out_of_range);
  EXPECT_THROW(buffer.upload(sink, sizeof sink, buffer.size() + 1), std::out_of_range);
  StorageBuffer moved = std::move(buffer);
  EXPECT_EQ(moved.size(), values.size() * sizeof(std::uint32_t));
  EXPECT_EQ(buffer.id(), 0u);  // NOLINT(bugprone-use-after-move): moved-from state is defined
  const StorageBuffer empty(context, 0);
  EXPECT_NO_THROW(empty.bind(0));
}

TEST(GlCompute, DispatchBeyondLimitsIsRefused) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const ComputeProgram program = ComputeProgram::from_embedded(context, "point_segment_distance");
  const auto too_many = static_cast<GLuint>(context.info().max_work_group_count[1]) + 1;
  try {
    dispatch(context, program, 1, too_many);
    ADD_FAILURE() << "no exception";
  } catch (const GlError& e) {
    EXPECT_NE(std::string(e.what()).find("GL_MAX_COMPUTE_WORK_GROUP_COUNT"), std::string::npos)
        << e.what();
  }
  EXPECT_EQ(group_count(0, 64), 0u);
  EXPECT_EQ(group_count(64, 64), 1u);
  EXPECT_EQ(group_count(65, 64), 2u);
  EXPECT_THROW(group_count(1, 0), std::invalid_argument);
}

TEST(GlCompute, GpuTimerMeasuresWork) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  if (!GpuTimer::supported(context)) {
    GTEST_SKIP() << "no GL_TIME_ELAPSED counter bits on " << context.renderer();
  }
  const Scene scene = random_scene(4096, 64, 99);
  const ComputeProgram program = ComputeProgram::from_embedded(context, "point_segment_distance");
  StorageBuffer points = StorageBuffer::from_vector(context, scene.points);
  StorageBuffer segments = StorageBuffer::from_vector(context, scene.segments);
  StorageBuffer index(context, 4096 * 4);
  StorageBuffer distance(context, 4096 * 4);
  points.bind(0);
  segments.bind(1);
  index.bind(2);
  distance.bind(3);
  program.set_uint("point_count", 4096);
  program.set_uint("segment_count", 64);
  program.set_uint("first_point", 0);
  GpuTimer timer(context);
  timer.begin();
  dispatch(context, program, group_count(4096, program.local_size()[0]));
  timer.end();
  // Only the query mechanics are checked: llvmpipe's counter does not cover compute work.
  const double ms = timer.elapsed_ms();
  EXPECT_GE(ms, 0.0);
  EXPECT_LT(ms, 60'000.0);
  memory_barrier(context);
  const std::vector<std::uint32_t> nearest = index.download_vector<std::uint32_t>(4096);
  EXPECT_LT(*std::max_element(nearest.begin(), nearest.end()), 64u);
}

}  // namespace
}  // namespace vproxq::gl
