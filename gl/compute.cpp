#include "gl/compute.hpp"

#include <limits>
#include <stdexcept>
#include <utility>

namespace vproxq::gl {

namespace {

std::string shader_info_log(const GlFunctions& gl, GLuint shader) {
  GLint length = 0;
  gl.GetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  check_gl(gl, "glGetShaderiv(GL_INFO_LOG_LENGTH)");
  if (length <= 1) return {};
  std::string log(static_cast<std::size_t>(length), '\0');
  GLsizei written = 0;
  gl.GetShaderInfoLog(shader, length, &written, log.data());
  check_gl(gl, "glGetShaderInfoLog");
  log.resize(static_cast<std::size_t>(written));
  return log;
}

std::string program_info_log(const GlFunctions& gl, GLuint program) {
  GLint length = 0;
  gl.GetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
  check_gl(gl, "glGetProgramiv(GL_INFO_LOG_LENGTH)");
  if (length <= 1) return {};
  std::string log(static_cast<std::size_t>(length), '\0');
  GLsizei written = 0;
  gl.GetProgramInfoLog(program, length, &written, log.data());
  check_gl(gl, "glGetProgramInfoLog");
  log.resize(static_cast<std::size_t>(written));
  return log;
}

/// Deletes a shader object when leaving scope (the program keeps what it needs after linking).
struct ShaderGuard {
  const GlFunctions& gl;
  GLuint shader;
  ~ShaderGuard() { gl.DeleteShader(shader); }
};

}  // namespace

// ComputeProgram --------------------------------------------------------------------------

ComputeProgram::ComputeProgram(const Context& context, std::string label,
                               const std::string& source)
    : gl_(&context.gl()), label_(std::move(label)) {
  const GlFunctions& gl = *gl_;
  const GLuint shader = gl.CreateShader(GL_COMPUTE_SHADER);
  check_gl(gl, "glCreateShader(GL_COMPUTE_SHADER)");
  if (shader == 0) throw GlError("glCreateShader(GL_COMPUTE_SHADER) returned 0");
  const ShaderGuard guard{gl, shader};

  if (source.size() > static_cast<std::size_t>(std::numeric_limits<GLint>::max())) {
    throw ShaderError("compute shader '" + label_ + "': source too long");
  }
  const GLchar* text = source.data();
  const auto length = static_cast<GLint>(source.size());
  gl.ShaderSource(shader, 1, &text, &length);
  check_gl(gl, "glShaderSource");
  gl.CompileShader(shader);
  check_gl(gl, "glCompileShader");
  GLint compiled = GL_FALSE;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &compiled);
  check_gl(gl, "glGetShaderiv(GL_COMPILE_STATUS)");
  const std::string compile_log = shader_info_log(gl, shader);
  if (compiled != GL_TRUE) {
    throw ShaderError("compute shader '" + label_ + "' failed to compile:\n" +
                      (compile_log.empty() ? "(empty compile log)" : compile_log));
  }

  program_ = gl.CreateProgram();
  check_gl(gl, "glCreateProgram");
  if (program_ == 0) throw GlError("glCreateProgram returned 0");
  try {
    gl.AttachShader(program_, shader);
    check_gl(gl, "glAttachShader");
    gl.LinkProgram(program_);
    check_gl(gl, "glLinkProgram");
    gl.DetachShader(program_, shader);
    check_gl(gl, "glDetachShader");
    GLint linked = GL_FALSE;
    gl.GetProgramiv(program_, GL_LINK_STATUS, &linked);
    check_gl(gl, "glGetProgramiv(GL_LINK_STATUS)");
    const std::string link_log = program_info_log(gl, program_);
    if (linked != GL_TRUE) {
      throw ShaderError("compute program '" + label_ + "' failed to link:\n" +
                        (link_log.empty() ? "(empty link log)" : link_log));
    }
    build_log_ = compile_log;
    if (!link_log.empty()) build_log_ += (build_log_.empty() ? "" : "\n") + link_log;
    GLint size[3] = {1, 1, 1};
    gl.GetProgramiv(program_, GL_COMPUTE_WORK_GROUP_SIZE, size);
    check_gl(gl, "glGetProgramiv(GL_COMPUTE_WORK_GROUP_SIZE)");
    for (int axis = 0; axis < 3; ++axis) local_size_[axis] = static_cast<GLuint>(size[axis]);
  } catch (...) {
    gl.DeleteProgram(program_);
    program_ = 0;
    throw;
  }
}

ComputeProgram ComputeProgram::from_embedded(const Context& context, std::string_view name,
                                             const ShaderDefines& defines) {
  return ComputeProgram(context, std::string(name), build_shader_source(name, defines));
}

ComputeProgram::ComputeProgram(ComputeProgram&& other) noexcept
    : gl_(other.gl_),
      program_(std::exchange(other.program_, 0)),
      label_(std::move(other.label_)),
      build_log_(std::move(other.build_log_)),
      local_size_(other.local_size_) {}

ComputeProgram& ComputeProgram::operator=(ComputeProgram&& other) noexcept {
  if (this != &other) {
    if (program_ != 0) gl_->DeleteProgram(program_);
    gl_ = other.gl_;
    program_ = std::exchange(other.program_, 0);
    label_ = std::move(other.label_);
    build_log_ = std::move(other.build_log_);
    local_size_ = other.local_size_;
  }
  return *this;
}

ComputeProgram::~ComputeProgram() {
  if (program_ != 0) gl_->DeleteProgram(program_);
}

GLint ComputeProgram::uniform_location(const char* name) const {
  const GLint location = gl_->GetUniformLocation(program_, name);
  check_gl(*gl_, "glGetUniformLocation");
  if (location < 0) {
    throw GlError("compute program '" + label_ + "' has no active uniform '" + name + "'");
  }
  return location;
}

void ComputeProgram::set_int(const char* name, GLint value) const {
  gl_->ProgramUniform1i(program_, uniform_location(name), value);
  check_gl(*gl_, "glProgramUniform1i");
}

void ComputeProgram::set_uint(const char* name, GLuint value) const {
  gl_->ProgramUniform1ui(program_, uniform_location(name), value);
  check_gl(*gl_, "glProgramUniform1ui");
}

void ComputeProgram::set_float(const char* name, GLfloat value) const {
  gl_->ProgramUniform1f(program_, uniform_location(name), value);
  check_gl(*gl_, "glProgramUniform1f");
}

// StorageBuffer ---------------------------------------------------------------------------

namespace {

/// glBufferData with size 0 is legal but binding an empty store is not portable; empty
/// buffers get this many bytes (size() still reports 0).
constexpr std::size_t kMinimumAllocation = 16;

void check_range(std::size_t offset, std::size_t bytes, std::size_t size, const char* what) {
  if (offset > size || bytes > size - offset) {
    throw std::out_of_range(std::string("StorageBuffer::") + what + ": bytes [" +
                            std::to_string(offset) + ", " + std::to_string(offset + bytes) +
                            ") outside the buffer of " + std::to_string(size) + " bytes");
  }
}

}  // namespace

StorageBuffer::StorageBuffer(const Context& context, std::size_t bytes, GLenum usage)
    : gl_(&context.gl()), info_(&context.info()), size_(bytes) {
  const GlFunctions& gl = *gl_;
  gl.GenBuffers(1, &buffer_);
  check_gl(gl, "glGenBuffers");
  try {
    gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, buffer_);
    check_gl(gl, "glBindBuffer(GL_SHADER_STORAGE_BUFFER)");
    const std::size_t allocation = bytes < kMinimumAllocation ? kMinimumAllocation : bytes;
    gl.BufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(allocation), nullptr, usage);
    check_gl(gl, ("glBufferData(" + std::to_string(allocation) + " bytes)").c_str());
    gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    check_gl(gl, "glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0)");
  } catch (...) {
    gl.DeleteBuffers(1, &buffer_);
    throw;
  }
}

StorageBuffer::StorageBuffer(StorageBuffer&& other) noexcept
    : gl_(other.gl_),
      info_(other.info_),
      buffer_(std::exchange(other.buffer_, 0)),
      size_(std::exchange(other.size_, 0)) {}

StorageBuffer& StorageBuffer::operator=(StorageBuffer&& other) noexcept {
  if (this != &other) {
    if (buffer_ != 0) gl_->DeleteBuffers(1, &buffer_);
    gl_ = other.gl_;
    info_ = other.info_;
    buffer_ = std::exchange(other.buffer_, 0);
    size_ = std::exchange(other.size_, 0);
  }
  return *this;
}

StorageBuffer::~StorageBuffer() {
  if (buffer_ != 0) gl_->DeleteBuffers(1, &buffer_);
}

void StorageBuffer::upload(const void* data, std::size_t bytes, std::size_t offset) {
  check_range(offset, bytes, size_, "upload");
  if (bytes == 0) return;
  const GlFunctions& gl = *gl_;
  // GL_COPY_WRITE_BUFFER: a binding point no shader reads, so no shader binding is disturbed.
  gl.BindBuffer(GL_COPY_WRITE_BUFFER, buffer_);
  check_gl(gl, "glBindBuffer(GL_COPY_WRITE_BUFFER)");
  gl.BufferSubData(GL_COPY_WRITE_BUFFER, static_cast<GLintptr>(offset),
                   static_cast<GLsizeiptr>(bytes), data);
  check_gl(gl, "glBufferSubData");
  gl.BindBuffer(GL_COPY_WRITE_BUFFER, 0);
  check_gl(gl, "glBindBuffer(GL_COPY_WRITE_BUFFER, 0)");
}

void StorageBuffer::download(void* data, std::size_t bytes, std::size_t offset) const {
  check_range(offset, bytes, size_, "download");
  if (bytes == 0) return;
  const GlFunctions& gl = *gl_;
  gl.BindBuffer(GL_COPY_READ_BUFFER, buffer_);
  check_gl(gl, "glBindBuffer(GL_COPY_READ_BUFFER)");
  gl.GetBufferSubData(GL_COPY_READ_BUFFER, static_cast<GLintptr>(offset),
                      static_cast<GLsizeiptr>(bytes), data);
  check_gl(gl, "glGetBufferSubData");
  gl.BindBuffer(GL_COPY_READ_BUFFER, 0);
  check_gl(gl, "glBindBuffer(GL_COPY_READ_BUFFER, 0)");
}

void StorageBuffer::clear_to_zero() { clear_to_zero(size_); }

void StorageBuffer::clear_to_zero(std::size_t bytes) {
  check_range(0, bytes, size_, "clear_to_zero");
  if (bytes == 0) return;
  const GlFunctions& gl = *gl_;
  gl.BindBuffer(GL_COPY_WRITE_BUFFER, buffer_);
  check_gl(gl, "glBindBuffer(GL_COPY_WRITE_BUFFER)");
  if (bytes % 4 == 0) {
    gl.ClearBufferSubData(GL_COPY_WRITE_BUFFER, GL_R32UI, 0, static_cast<GLsizeiptr>(bytes),
                          GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
  } else {
    gl.ClearBufferSubData(GL_COPY_WRITE_BUFFER, GL_R8UI, 0, static_cast<GLsizeiptr>(bytes),
                          GL_RED_INTEGER, GL_UNSIGNED_BYTE, nullptr);
  }
  check_gl(gl, "glClearBufferSubData");
  gl.BindBuffer(GL_COPY_WRITE_BUFFER, 0);
  check_gl(gl, "glBindBuffer(GL_COPY_WRITE_BUFFER, 0)");
}

void StorageBuffer::bind(GLuint binding) const {
  if (static_cast<std::int64_t>(size_) > info_->max_ssbo_block_size) {
    throw GlError("a storage buffer of " + std::to_string(size_) +
                  " bytes exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" +
                  std::to_string(info_->max_ssbo_block_size) + " bytes) of " + info_->gl_renderer +
                  "; a coarser --grid (or --voronoi=cpu) needs less");
  }
  if (static_cast<GLint>(binding) >= info_->max_ssbo_bindings) {
    throw GlError("storage buffer binding " + std::to_string(binding) +
                  " exceeds GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS (" +
                  std::to_string(info_->max_ssbo_bindings) + ")");
  }
  gl_->BindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, buffer_);
  check_gl(*gl_, "glBindBufferBase(GL_SHADER_STORAGE_BUFFER)");
}

// Dispatch, barriers, timing -------------------------------------------------------------

GLuint group_count(std::size_t items, GLuint local_size) {
  if (local_size == 0) throw std::invalid_argument("group_count: local size 0");
  const std::size_t groups = items / local_size + (items % local_size != 0 ? 1 : 0);
  if (groups > std::numeric_limits<GLuint>::max()) {
    throw std::out_of_range("group_count: " + std::to_string(items) + " items need " +
                            std::to_string(groups) + " work groups");
  }
  return static_cast<GLuint>(groups);
}

void dispatch(const Context& context, const ComputeProgram& program, GLuint groups_x,
              GLuint groups_y, GLuint groups_z) {
  const ContextInfo& info = context.info();
  const GLuint groups[3] = {groups_x, groups_y, groups_z};
  for (int axis = 0; axis < 3; ++axis) {
    if (groups[axis] > static_cast<GLuint>(info.max_work_group_count[axis])) {
      throw GlError("dispatch of '" + program.label() + "': " + std::to_string(groups[axis]) +
                    " work groups along axis " + std::to_string(axis) +
                    " exceed GL_MAX_COMPUTE_WORK_GROUP_COUNT (" +
                    std::to_string(info.max_work_group_count[axis]) + ")");
    }
  }
  const GlFunctions& gl = context.gl();
  gl.UseProgram(program.id());
  check_gl(gl, "glUseProgram");
  gl.DispatchCompute(groups_x, groups_y, groups_z);
  check_gl(gl, "glDispatchCompute");
}

void memory_barrier(const Context& context, GLbitfield barriers) {
  context.gl().MemoryBarrier(barriers);
  check_gl(context.gl(), "glMemoryBarrier");
}

void finish(const Context& context) {
  context.gl().Finish();
  check_gl(context.gl(), "glFinish");
}

GpuTimer::GpuTimer(const Context& context) : gl_(&context.gl()) {
  gl_->GenQueries(1, &query_);
  check_gl(*gl_, "glGenQueries");
}

GpuTimer::GpuTimer(GpuTimer&& other) noexcept
    : gl_(other.gl_), query_(std::exchange(other.query_, 0)) {}

GpuTimer& GpuTimer::operator=(GpuTimer&& other) noexcept {
  if (this != &other) {
    if (query_ != 0) gl_->DeleteQueries(1, &query_);
    gl_ = other.gl_;
    query_ = std::exchange(other.query_, 0);
  }
  return *this;
}

GpuTimer::~GpuTimer() {
  if (query_ != 0) gl_->DeleteQueries(1, &query_);
}

bool GpuTimer::supported(const Context& context) {
  GLint bits = 0;
  context.gl().GetQueryiv(GL_TIME_ELAPSED, GL_QUERY_COUNTER_BITS, &bits);
  check_gl(context.gl(), "glGetQueryiv(GL_TIME_ELAPSED, GL_QUERY_COUNTER_BITS)");
  return bits > 0;
}

void GpuTimer::begin() {
  gl_->BeginQuery(GL_TIME_ELAPSED, query_);
  check_gl(*gl_, "glBeginQuery(GL_TIME_ELAPSED)");
}

void GpuTimer::end() {
  gl_->EndQuery(GL_TIME_ELAPSED);
  check_gl(*gl_, "glEndQuery(GL_TIME_ELAPSED)");
}

double GpuTimer::elapsed_ms() const {
  GLuint64 nanoseconds = 0;
  gl_->GetQueryObjectui64v(query_, GL_QUERY_RESULT, &nanoseconds);
  check_gl(*gl_, "glGetQueryObjectui64v(GL_QUERY_RESULT)");
  return static_cast<double>(nanoseconds) * 1e-6;
}

}  // namespace vproxq::gl
