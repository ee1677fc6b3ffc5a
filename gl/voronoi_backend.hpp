#pragma once
// Stage II on the GPU: the DiscreteVoronoiBackend of core/voronoi/discrete_voronoi.hpp as an
// OpenGL 4.3 compute shader (shaders/dvd2_gather.comp), float32, one invocation per sample
// voxel gathering the triangles of the bins around it. Same algorithm and output as the CPU
// twin (make_cpu_voronoi_backend), up to distance_error_bound().
#include <cstddef>
#include <string>

#include "core/voronoi/discrete_voronoi.hpp"
#include "gl/compute.hpp"

namespace vproxq::gl {

struct GlVoronoiOptions {
  GLuint local_size = 64;  ///< work group size (LOCAL_SIZE define of the shader)
  /// Work groups per dispatch; 0: GL_MAX_COMPUTE_WORK_GROUP_COUNT. Sample voxels are processed
  /// in batches of local_size * this (fewer when the per-batch buffers would exceed
  /// GL_MAX_SHADER_STORAGE_BLOCK_SIZE). Tests use small values to exercise batching.
  GLuint max_groups_per_dispatch = 0;
  /// Threads of the CPU twin that computes the samples the shader could not finish (a
  /// driver's loop cap); 0: all cores.
  int cpu_threads = 0;
};

/// The GL compute backend ("gpu").
///
/// Lifetime: the backend keeps a reference to `context` (it does not own it). The Context
/// object must outlive the backend and must not be moved while the backend exists, and it must
/// be current on the thread that constructs the backend, calls compute() and destroys it.
class GlVoronoiBackend final : public DiscreteVoronoiBackend {
 public:
  /// Compiles the shader. Throws ShaderError / GlError on GL failures.
  explicit GlVoronoiBackend(const Context& context, const GlVoronoiOptions& options = {});

  std::string name() const override { return "gpu"; }
  /// context.renderer(), e.g. "llvmpipe (LLVM 15.0.6, 256 bits); OpenGL 4.5 (Core Profile) ...".
  std::string device() const override;
  /// float32_error_bound(extent).
  double distance_error_bound(double extent) const override;
  /// Throws std::invalid_argument for inconsistent input (validate_dvd_input()) or a grid the
  /// shader cannot address (a side of 2^23 voxels or more),
  /// GlError when a buffer exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE or a GL call fails.
  /// upload_ms includes building the per-triangle info on the host.
  DvdOutput compute(const DvdInput& in) override;

  /// δ_precision of the shader: the largest error of a reported distance (below the band)
  /// against the exact distance of the double input, when every coordinate (triangle corners
  /// and sample points, relative to the grid origin) lies in [-extent, extent] and
  /// 2^-40 <= extent <= 2^60:  kFloat32ErrorUnits * 2^-24 * extent + 2^-48.
  /// Derivation in voronoi_backend.cpp.
  static double float32_error_bound(double extent);
  /// The constant of float32_error_bound(): the derivation gives 569; rounded up to 1024.
  static constexpr double kFloat32ErrorUnits = 1024.0;

  /// Milliseconds spent compiling and linking the shader (in the constructor).
  double compile_ms() const { return compile_ms_; }
  /// Number of glDispatchCompute calls of the last compute().
  std::size_t last_dispatch_count() const { return last_dispatch_count_; }
  /// Samples of the last compute() that the shader could not finish (a driver's loop cap:
  /// shaders/dvd2_gather.comp) and the CPU twin computed instead.
  std::size_t last_redone() const { return last_redone_; }

 private:
  const Context& context_;
  GlVoronoiOptions options_;
  double compile_ms_ = 0;  // before program_: set while program_ is initialized
  ComputeProgram program_;
  std::size_t last_dispatch_count_ = 0;
  std::size_t last_redone_ = 0;
};

}  // namespace vproxq::gl
