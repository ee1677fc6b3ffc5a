// Shader embedding (generated at build time from shaders/*.comp) and source composition.
// No GL context needed.
#include "gl/shader_source.hpp"

#include "core/errors.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>

namespace vproxq::gl {
namespace {

TEST(ShaderSource, EmbedsEveryShaderFile) {
  const std::vector<std::string_view> names = shader_names();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  ASSERT_NE(std::find(names.begin(), names.end(), "point_segment_distance"), names.end());
  const std::string_view source = shader_source("point_segment_distance");
  EXPECT_NE(source.find("void main()"), std::string_view::npos);
  EXPECT_NE(source.find("point_segment_distance_squared"), std::string_view::npos);
  EXPECT_EQ(source.find("#version"), std::string_view::npos);
}

TEST(ShaderSource, UnknownShaderNamesTheKnownOnes) {
  try {
    shader_source("no_such_shader");
    ADD_FAILURE() << "no exception";
  } catch (const RuntimeError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("no_such_shader"), std::string::npos) << message;
    EXPECT_NE(message.find("point_segment_distance"), std::string::npos) << message;
  }
}

TEST(ShaderSource, PrependsVersionDefinesAndLineDirective) {
  const std::string source =
      compose_shader_source("void main() {}\n", {{"LOCAL_SIZE", "32"}, {"USE_FAST_PATH", ""}});
  EXPECT_EQ(source,
            "#version 430 core\n"
            "#define LOCAL_SIZE 32\n"
            "#define USE_FAST_PATH\n"
            "#line 1\n"
            "void main() {}\n");
  const std::string built = build_shader_source("point_segment_distance", {{"LOCAL_SIZE", "8"}});
  EXPECT_EQ(built.rfind("#version 430 core\n#define LOCAL_SIZE 8\n#line 1\n", 0), 0u);
  EXPECT_NE(built.find(shader_source("point_segment_distance")), std::string::npos);
}

TEST(ShaderSource, RejectsMalformedDefines) {
  EXPECT_THROW(compose_shader_source("", {{"1ABC", "1"}}), std::invalid_argument);
  EXPECT_THROW(compose_shader_source("", {{"", "1"}}), std::invalid_argument);
  EXPECT_THROW(compose_shader_source("", {{"A B", "1"}}), std::invalid_argument);
  EXPECT_THROW(compose_shader_source("", {{"A", "1\n#define B 2"}}), std::invalid_argument);
}

}  // namespace
}  // namespace vproxq::gl
