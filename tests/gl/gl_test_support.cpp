#include "gl_test_support.hpp"

#include <cstdlib>
#include <cstring>

namespace vproxq::gl::testing {

bool gl_required() {
  const char* value = std::getenv("VPROXQ_REQUIRE_GL");
  return value == nullptr || std::strcmp(value, "0") != 0;
}

const ContextResult& shared_context() {
  // Never destroyed: GL tests may run in any order up to process exit, and tearing down a
  // context from a static destructor races the driver's own exit handlers.
  static const ContextResult* const result = new ContextResult(try_create_context());
  if (*result) result->context->make_current();
  return *result;
}

}  // namespace vproxq::gl::testing
