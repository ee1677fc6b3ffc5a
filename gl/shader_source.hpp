#pragma once
// Compute shaders embedded into the binary, and the final source handed to the compiler.
//
// Every shaders/<name>.comp is embedded at build time (gl/cmake/embed_shaders.cmake, output in
// the build tree). Shader files have no #version line: at run time compose_shader_source()
// prepends "#version 430 core", the #define lines of the caller, and "#line 1" so that line
// numbers in compiler logs are those of the .comp file.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace vproxq::gl {

/// GLSL version line prepended to every shader (compute shaders need 4.30).
inline constexpr std::string_view kGlslVersionLine = "#version 430 core";

/// Embedded source of shaders/<name>.comp, `name` without the extension. Throws RuntimeError
/// naming the known shaders when there is no such shader.
std::string_view shader_source(std::string_view name);

/// Names of all embedded shaders, sorted.
std::vector<std::string_view> shader_names();

/// One `#define name value` line. `value` may be empty.
struct ShaderDefine {
  std::string name;
  std::string value;
};
using ShaderDefines = std::vector<ShaderDefine>;

/// "#version 430 core\n", one "#define NAME VALUE\n" per define in order, "#line 1\n", body.
/// Throws std::invalid_argument when a define name is not an identifier or a value spans lines.
std::string compose_shader_source(std::string_view body, const ShaderDefines& defines = {});

/// compose_shader_source(shader_source(name), defines).
std::string build_shader_source(std::string_view name, const ShaderDefines& defines = {});

namespace detail {
struct EmbeddedShader {
  std::string_view name;
  std::string_view source;
};
struct EmbeddedShaders {
  const EmbeddedShader* data;
  std::size_t size;
};
/// Defined in the generated file (sorted by name).
EmbeddedShaders embedded_shaders();
}  // namespace detail

}  // namespace vproxq::gl
