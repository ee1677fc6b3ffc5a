#include "gl/shader_source.hpp"

#include "core/errors.hpp"

#include <stdexcept>

namespace vproxq::gl {

namespace {

bool is_identifier(std::string_view name) {
  if (name.empty()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool letter = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_';
    const bool digit = c >= '0' && c <= '9';
    if (!letter && !(digit && i > 0)) return false;
  }
  return true;
}

}  // namespace

std::string_view shader_source(std::string_view name) {
  const detail::EmbeddedShaders shaders = detail::embedded_shaders();
  for (std::size_t i = 0; i < shaders.size; ++i) {
    if (shaders.data[i].name == name) return shaders.data[i].source;
  }
  std::string known;
  for (std::string_view each : shader_names()) {
    known += (known.empty() ? "" : ", ") + std::string(each);
  }
  throw RuntimeError("no embedded shader named '" + std::string(name) + "' (embedded: " +
                     (known.empty() ? "none" : known) + ")");
}

std::vector<std::string_view> shader_names() {
  const detail::EmbeddedShaders shaders = detail::embedded_shaders();
  std::vector<std::string_view> names;
  names.reserve(shaders.size);
  for (std::size_t i = 0; i < shaders.size; ++i) names.push_back(shaders.data[i].name);
  return names;
}

std::string compose_shader_source(std::string_view body, const ShaderDefines& defines) {
  std::string out(kGlslVersionLine);
  out += '\n';
  for (const ShaderDefine& define : defines) {
    if (!is_identifier(define.name)) {
      throw std::invalid_argument("shader define name '" + define.name +
                                  "' is not an identifier");
    }
    if (define.value.find_first_of("\r\n") != std::string::npos) {
      throw std::invalid_argument("shader define " + define.name + " has a multi-line value");
    }
    out += "#define " + define.name;
    if (!define.value.empty()) out += " " + define.value;
    out += '\n';
  }
  out += "#line 1\n";
  out += body;
  return out;
}

std::string build_shader_source(std::string_view name, const ShaderDefines& defines) {
  return compose_shader_source(shader_source(name), defines);
}

}  // namespace vproxq::gl
