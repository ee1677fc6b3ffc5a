#pragma once
// The self Stage II on the GPU: the SelfVoronoiBackend of core/voronoi/self_stage2.hpp as an
// OpenGL 4.3 compute shader (shaders/dvd_self_gather.comp appended to shaders/dvd2_gather.comp),
// float32, one invocation per sample. Same algorithm and output as the CPU twin
// (make_cpu_self_voronoi_backend), up to distance_error_bound().
#include <cstddef>
#include <string>

#include "core/voronoi/self_stage2.hpp"
#include "gl/compute.hpp"
#include "gl/voronoi_backend.hpp"

namespace vproxq::gl {

/// Lifetime and threading as GlVoronoiBackend: the Context must outlive the backend and be
/// current on the thread that constructs it, calls compute() and destroys it.
class GlSelfVoronoiBackend final : public SelfVoronoiBackend {
 public:
  /// Compiles the shader. Throws ShaderError / GlError on GL failures.
  explicit GlSelfVoronoiBackend(const Context& context, const GlVoronoiOptions& options = {});

  std::string name() const override { return "gpu"; }
  std::string device() const override;
  /// GlVoronoiBackend::float32_error_bound(extent): the distance arithmetic, sample points
  /// and input rounding are dvd2_gather's, and the result is the minimum of such distances
  /// over a subset of the triangles (the derivation in voronoi_backend.cpp covers it).
  double distance_error_bound(double extent) const override;
  /// Throws std::invalid_argument for inconsistent input (validate_self_dvd_input()) or a grid
  /// the shader cannot address, GlError when a buffer is too large or a GL call fails.
  SelfDvdOutput compute(const SelfDvdInput& in) override;

  /// The nearest triangle per sample of the last compute() (kNoIndex when none below the
  /// band), for tests.
  const std::vector<std::int32_t>& last_nearest() const { return last_nearest_; }
  std::size_t last_dispatch_count() const { return last_dispatch_count_; }
  /// Samples of the last compute() that the shader could not finish (a driver's loop cap:
  /// shaders/dvd2_gather.comp) and the CPU twin computed instead.
  std::size_t last_redone() const { return last_redone_; }

 private:
  const Context& context_;
  GlVoronoiOptions options_;
  ComputeProgram program_;
  std::vector<std::int32_t> last_nearest_;
  std::size_t last_dispatch_count_ = 0;
  std::size_t last_redone_ = 0;
};

}  // namespace vproxq::gl
