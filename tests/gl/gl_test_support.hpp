#pragma once
// The GL test tier's context. Every test that needs GL starts with
//   VPROXQ_GL_CONTEXT_OR_FAIL(context);
// which declares `const vproxq::gl::Context& context` (one context per test process, made
// current again for each test). When no context can be made the test FAILS with the reason,
// unless the environment sets VPROXQ_REQUIRE_GL=0, in which case it is skipped. CI sets
// nothing and runs on Mesa llvmpipe: a broken GL path fails there.
#include "gl/egl_context.hpp"

#include <gtest/gtest.h>

namespace vproxq::gl::testing {

/// False only when $VPROXQ_REQUIRE_GL is "0".
bool gl_required();

/// The process-wide test context (created on first use), made current on the calling thread.
const ContextResult& shared_context();

}  // namespace vproxq::gl::testing

#define VPROXQ_GL_CONTEXT_OR_FAIL(name)                                                      \
  const ::vproxq::gl::ContextResult& name##_result = ::vproxq::gl::testing::shared_context(); \
  if (!name##_result) {                                                                      \
    if (::vproxq::gl::testing::gl_required()) {                                              \
      FAIL() << "no OpenGL context (set VPROXQ_REQUIRE_GL=0 to skip GL tests): "             \
             << name##_result.error;                                                         \
    } else {                                                                                 \
      GTEST_SKIP() << "VPROXQ_REQUIRE_GL=0 and no OpenGL context: " << name##_result.error;  \
    }                                                                                        \
  }                                                                                          \
  const ::vproxq::gl::Context& name = *name##_result.context
