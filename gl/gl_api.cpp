#include "gl/gl_api.hpp"

#include <cstdio>

namespace vproxq::gl {

std::string gl_error_name(GLenum error) {
  switch (error) {
    case GL_NO_ERROR: return "GL_NO_ERROR";
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_STACK_OVERFLOW: return "GL_STACK_OVERFLOW";
    case GL_STACK_UNDERFLOW: return "GL_STACK_UNDERFLOW";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_CONTEXT_LOST: return "GL_CONTEXT_LOST";
    default: break;
  }
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "unknown GL error 0x%04X", static_cast<unsigned>(error));
  return buffer;
}

void check_gl(const GlFunctions& gl, const char* call) {
  // glGetError returns one set flag per call; a lost context keeps returning
  // GL_CONTEXT_LOST, so the loop is bounded.
  constexpr int kMaxErrorFlags = 8;
  std::string errors;
  for (int i = 0; i < kMaxErrorFlags; ++i) {
    const GLenum error = gl.GetError();
    if (error == GL_NO_ERROR) break;
    if (!errors.empty()) errors += ", ";
    errors += gl_error_name(error);
    if (error == GL_CONTEXT_LOST) break;
  }
  if (!errors.empty()) throw GlError(std::string(call) + " failed: " + errors);
}

}  // namespace vproxq::gl
