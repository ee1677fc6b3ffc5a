#pragma once
// The OpenGL entry points vproxq uses, loaded at run time through eglGetProcAddress, and the
// GL error checking every call goes through. Types and constants come from the Khronos
// header GL/glcorearb.h; nothing here links against libGL / libOpenGL.
#include "core/errors.hpp"

#include <GL/glcorearb.h>

#include <string>

namespace vproxq::gl {

/// Every GL function vproxq calls: X(Name, PFN type). The loader resolves "gl" #Name and
/// fails, naming the function, when one is missing.
#define VPROXQ_GL_FUNCTIONS(X)                                  \
  X(GetError, PFNGLGETERRORPROC)                                \
  X(GetString, PFNGLGETSTRINGPROC)                              \
  X(GetIntegerv, PFNGLGETINTEGERVPROC)                          \
  X(GetIntegeri_v, PFNGLGETINTEGERI_VPROC)                      \
  X(GetInteger64v, PFNGLGETINTEGER64VPROC)                      \
  X(Finish, PFNGLFINISHPROC)                                    \
  X(Flush, PFNGLFLUSHPROC)                                      \
  X(CreateShader, PFNGLCREATESHADERPROC)                        \
  X(ShaderSource, PFNGLSHADERSOURCEPROC)                        \
  X(CompileShader, PFNGLCOMPILESHADERPROC)                      \
  X(GetShaderiv, PFNGLGETSHADERIVPROC)                          \
  X(GetShaderInfoLog, PFNGLGETSHADERINFOLOGPROC)                \
  X(DeleteShader, PFNGLDELETESHADERPROC)                        \
  X(CreateProgram, PFNGLCREATEPROGRAMPROC)                      \
  X(AttachShader, PFNGLATTACHSHADERPROC)                        \
  X(DetachShader, PFNGLDETACHSHADERPROC)                        \
  X(LinkProgram, PFNGLLINKPROGRAMPROC)                          \
  X(GetProgramiv, PFNGLGETPROGRAMIVPROC)                        \
  X(GetProgramInfoLog, PFNGLGETPROGRAMINFOLOGPROC)              \
  X(DeleteProgram, PFNGLDELETEPROGRAMPROC)                      \
  X(UseProgram, PFNGLUSEPROGRAMPROC)                            \
  X(GetUniformLocation, PFNGLGETUNIFORMLOCATIONPROC)            \
  X(ProgramUniform1i, PFNGLPROGRAMUNIFORM1IPROC)                \
  X(ProgramUniform1ui, PFNGLPROGRAMUNIFORM1UIPROC)              \
  X(ProgramUniform1f, PFNGLPROGRAMUNIFORM1FPROC)                \
  X(ProgramUniform3f, PFNGLPROGRAMUNIFORM3FPROC)                \
  X(GenBuffers, PFNGLGENBUFFERSPROC)                            \
  X(DeleteBuffers, PFNGLDELETEBUFFERSPROC)                      \
  X(BindBuffer, PFNGLBINDBUFFERPROC)                            \
  X(BindBufferBase, PFNGLBINDBUFFERBASEPROC)                    \
  X(BufferData, PFNGLBUFFERDATAPROC)                            \
  X(BufferSubData, PFNGLBUFFERSUBDATAPROC)                      \
  X(GetBufferSubData, PFNGLGETBUFFERSUBDATAPROC)                \
  X(ClearBufferSubData, PFNGLCLEARBUFFERSUBDATAPROC)            \
  X(DispatchCompute, PFNGLDISPATCHCOMPUTEPROC)                  \
  X(MemoryBarrier, PFNGLMEMORYBARRIERPROC)                      \
  X(GenQueries, PFNGLGENQUERIESPROC)                            \
  X(DeleteQueries, PFNGLDELETEQUERIESPROC)                      \
  X(BeginQuery, PFNGLBEGINQUERYPROC)                            \
  X(EndQuery, PFNGLENDQUERYPROC)                                \
  X(GetQueryiv, PFNGLGETQUERYIVPROC)                            \
  X(GetQueryObjectui64v, PFNGLGETQUERYOBJECTUI64VPROC)

/// Function table of one context. Call as `gl.BufferData(...)`. Owned by gl::Context; its
/// address stays valid for the context's lifetime (also across moves of the Context).
struct GlFunctions {
#define VPROXQ_GL_DECLARE(name, type) type name = nullptr;
  VPROXQ_GL_FUNCTIONS(VPROXQ_GL_DECLARE)
#undef VPROXQ_GL_DECLARE
};

/// A failed GL call, or a GL object that could not be made (compile/link errors are
/// ShaderError, see compute.hpp). The message names the call and the decoded error.
struct GlError : RuntimeError {
  using RuntimeError::RuntimeError;
};

/// "GL_INVALID_ENUM", "GL_OUT_OF_MEMORY", ...; unknown codes as "unknown GL error 0x1234".
std::string gl_error_name(GLenum error);

/// Drains glGetError (several flags can be set) and throws GlError "`call` failed: GL_..."
/// when any was set. `call` names the GL call just made, e.g. "glBufferData".
void check_gl(const GlFunctions& gl, const char* call);

}  // namespace vproxq::gl
