#pragma once
// Minimal OpenGL compute helpers: programs, shader storage buffers, dispatch, barriers and
// timing. Every GL call is checked (GlError names the call and the decoded error).
//
// All objects keep a pointer to their Context's function table: the Context must be current
// on the calling thread and must outlive them.
#include "gl/egl_context.hpp"
#include "gl/gl_api.hpp"
#include "gl/shader_source.hpp"

#include <array>
#include <chrono>
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace vproxq::gl {

/// A shader that did not compile or a program that did not link. The message names the
/// shader and holds the driver's full info log.
struct ShaderError : GlError {
  using GlError::GlError;
};

/// A linked compute program. Move-only; deletes the program on destruction.
class ComputeProgram {
 public:
  /// Compiles `source` (complete, with its #version line) and links it. `label` names the
  /// program in error messages. Throws ShaderError with the compile or link log.
  ComputeProgram(const Context& context, std::string label, const std::string& source);
  /// Compiles the embedded shaders/<name>.comp with `defines` (build_shader_source()).
  static ComputeProgram from_embedded(const Context& context, std::string_view name,
                                      const ShaderDefines& defines = {});

  ComputeProgram(ComputeProgram&& other) noexcept;
  ComputeProgram& operator=(ComputeProgram&& other) noexcept;
  ComputeProgram(const ComputeProgram&) = delete;
  ComputeProgram& operator=(const ComputeProgram&) = delete;
  ~ComputeProgram();

  GLuint id() const { return program_; }
  const std::string& label() const { return label_; }
  /// Warnings of a successful compile and link (the info logs), possibly empty.
  const std::string& build_log() const { return build_log_; }
  /// The layout(local_size_x/y/z) of the shader (GL_COMPUTE_WORK_GROUP_SIZE).
  const std::array<GLuint, 3>& local_size() const { return local_size_; }

  /// Location of an active uniform; throws GlError when there is none by that name (unused
  /// uniforms are removed by the compiler, so this also catches typos in either place).
  GLint uniform_location(const char* name) const;
  void set_int(const char* name, GLint value) const;
  void set_uint(const char* name, GLuint value) const;
  void set_float(const char* name, GLfloat value) const;

 private:
  const GlFunctions* gl_ = nullptr;
  GLuint program_ = 0;
  std::string label_;
  std::string build_log_;
  std::array<GLuint, 3> local_size_{1, 1, 1};
};

/// A buffer object used as shader storage buffer (SSBO). Move-only.
class StorageBuffer {
 public:
  /// Allocates `bytes` bytes of undefined content. `usage` is a glBufferData hint.
  StorageBuffer(const Context& context, std::size_t bytes, GLenum usage = GL_DYNAMIC_DRAW);
  /// A buffer holding a copy of `data`.
  template <class T>
  static StorageBuffer from_vector(const Context& context, const std::vector<T>& data,
                                   GLenum usage = GL_STATIC_DRAW) {
    StorageBuffer buffer(context, data.size() * sizeof(T), usage);
    buffer.upload(data.data(), data.size() * sizeof(T));
    return buffer;
  }

  StorageBuffer(StorageBuffer&& other) noexcept;
  StorageBuffer& operator=(StorageBuffer&& other) noexcept;
  StorageBuffer(const StorageBuffer&) = delete;
  StorageBuffer& operator=(const StorageBuffer&) = delete;
  ~StorageBuffer();

  GLuint id() const { return buffer_; }
  std::size_t size() const { return size_; }

  /// Copies `bytes` bytes from `data` to the buffer at byte `offset` (glBufferSubData).
  void upload(const void* data, std::size_t bytes, std::size_t offset = 0);
  /// Copies `bytes` bytes at byte `offset` into `data` (glGetBufferSubData; waits for the GPU).
  /// After a dispatch that wrote the buffer, call memory_barrier() first.
  void download(void* data, std::size_t bytes, std::size_t offset = 0) const;
  /// `count` elements of type T starting at element `first`.
  template <class T>
  std::vector<T> download_vector(std::size_t count, std::size_t first = 0) const {
    std::vector<T> out(count);
    download(out.data(), count * sizeof(T), first * sizeof(T));
    return out;
  }
  /// Sets every byte to zero.
  void clear_to_zero();
  /// Sets the first `bytes` bytes to zero (glClearBufferSubData, in 32-bit words where
  /// `bytes` is a multiple of 4). Throws std::out_of_range past size().
  void clear_to_zero(std::size_t bytes);
  /// Binds the whole buffer to `layout(binding = binding)` shader storage blocks. Throws
  /// GlError when the buffer is larger than GL_MAX_SHADER_STORAGE_BLOCK_SIZE.
  void bind(GLuint binding) const;

 private:
  const GlFunctions* gl_ = nullptr;
  const ContextInfo* info_ = nullptr;
  GLuint buffer_ = 0;
  std::size_t size_ = 0;
};

/// Number of work groups of `local_size` invocations covering `items` items (rounded up).
GLuint group_count(std::size_t items, GLuint local_size);

/// Runs `program` on groups_x × groups_y × groups_z work groups (glUseProgram +
/// glDispatchCompute). Throws GlError when a count exceeds GL_MAX_COMPUTE_WORK_GROUP_COUNT.
void dispatch(const Context& context, const ComputeProgram& program, GLuint groups_x,
              GLuint groups_y = 1, GLuint groups_z = 1);

/// glMemoryBarrier. The default makes shader storage writes visible to later dispatches and to
/// StorageBuffer::upload/download.
void memory_barrier(const Context& context,
                    GLbitfield barriers = GL_SHADER_STORAGE_BARRIER_BIT |
                                          GL_BUFFER_UPDATE_BARRIER_BIT);

/// glFinish: returns when all queued GL work is done.
void finish(const Context& context);

/// Wall-clock milliseconds spent in `work` plus the GL work it queued: glFinish before (so
/// that earlier work is not counted) and after.
template <class Work>
double finish_timed_ms(const Context& context, Work&& work) {
  finish(context);
  const auto start = std::chrono::steady_clock::now();
  work();
  finish(context);
  const std::chrono::duration<double, std::milli> elapsed =
      std::chrono::steady_clock::now() - start;
  return elapsed.count();
}

/// GPU time of the commands between begin() and end() (a GL_TIME_ELAPSED query). Only one
/// GL_TIME_ELAPSED query may be active at a time. Move-only. On llvmpipe the counter does not
/// cover compute dispatches (it reads ~0): use finish_timed_ms() there.
class GpuTimer {
 public:
  explicit GpuTimer(const Context& context);
  GpuTimer(GpuTimer&& other) noexcept;
  GpuTimer& operator=(GpuTimer&& other) noexcept;
  GpuTimer(const GpuTimer&) = delete;
  GpuTimer& operator=(const GpuTimer&) = delete;
  ~GpuTimer();

  /// False when the implementation has no GL_TIME_ELAPSED counter bits (results would be 0).
  static bool supported(const Context& context);

  void begin();
  void end();
  /// Milliseconds between begin() and end(); waits for the GPU to finish them.
  double elapsed_ms() const;

 private:
  const GlFunctions* gl_ = nullptr;
  GLuint query_ = 0;
};

/// Per-call times of a GPU computation, in milliseconds (wall clock, glFinish-bounded).
struct GpuTimings {
  double upload_ms = 0;    ///< buffer creation and host-to-GPU copies
  double compute_ms = 0;   ///< dispatches up to the end of the GPU work
  double readback_ms = 0;  ///< GPU-to-host copies
  /// GL_TIME_ELAPSED of the dispatches; -1 when the query is unsupported or the renderer is
  /// a software one (llvmpipe's counter does not cover compute dispatches: it reads ~0).
  double gpu_compute_ms = -1;
};

}  // namespace vproxq::gl
