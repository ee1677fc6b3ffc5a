#include "gl/egl_context.hpp"

// Khronos headers for types and constants only: no prototypes, no X11, nothing to link.
#define EGL_NO_X11 1
#define EGL_EGL_PROTOTYPES 0
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <dlfcn.h>

#include <cstdio>
#include <cstdlib>
#include <map>
#include <mutex>
#include <sstream>
#include <utility>

namespace vproxq::gl {

std::string egl_error_name(std::int32_t error) {
  const char* name = nullptr;
  switch (error) {
    case EGL_SUCCESS: name = "EGL_SUCCESS"; break;
    case EGL_NOT_INITIALIZED: name = "EGL_NOT_INITIALIZED"; break;
    case EGL_BAD_ACCESS: name = "EGL_BAD_ACCESS"; break;
    case EGL_BAD_ALLOC: name = "EGL_BAD_ALLOC"; break;
    case EGL_BAD_ATTRIBUTE: name = "EGL_BAD_ATTRIBUTE"; break;
    case EGL_BAD_CONFIG: name = "EGL_BAD_CONFIG"; break;
    case EGL_BAD_CONTEXT: name = "EGL_BAD_CONTEXT"; break;
    case EGL_BAD_CURRENT_SURFACE: name = "EGL_BAD_CURRENT_SURFACE"; break;
    case EGL_BAD_DISPLAY: name = "EGL_BAD_DISPLAY"; break;
    case EGL_BAD_MATCH: name = "EGL_BAD_MATCH"; break;
    case EGL_BAD_NATIVE_PIXMAP: name = "EGL_BAD_NATIVE_PIXMAP"; break;
    case EGL_BAD_NATIVE_WINDOW: name = "EGL_BAD_NATIVE_WINDOW"; break;
    case EGL_BAD_PARAMETER: name = "EGL_BAD_PARAMETER"; break;
    case EGL_BAD_SURFACE: name = "EGL_BAD_SURFACE"; break;
    case EGL_CONTEXT_LOST: name = "EGL_CONTEXT_LOST"; break;
    case EGL_BAD_DEVICE_EXT: name = "EGL_BAD_DEVICE_EXT"; break;
    default: break;
  }
  char buffer[64];
  if (name != nullptr) {
    std::snprintf(buffer, sizeof buffer, "%s (0x%04X)", name, static_cast<unsigned>(error));
  } else {
    std::snprintf(buffer, sizeof buffer, "unknown EGL error 0x%04X", static_cast<unsigned>(error));
  }
  return buffer;
}

namespace {

// Core EGL entry points: resolved with dlsym, because before EGL 1.5 eglGetProcAddress
// need not return core functions.
#define VPROXQ_EGL_FUNCTIONS(X)                     \
  X(GetProcAddress, PFNEGLGETPROCADDRESSPROC)       \
  X(GetError, PFNEGLGETERRORPROC)                   \
  X(GetDisplay, PFNEGLGETDISPLAYPROC)               \
  X(Initialize, PFNEGLINITIALIZEPROC)               \
  X(Terminate, PFNEGLTERMINATEPROC)                 \
  X(QueryString, PFNEGLQUERYSTRINGPROC)             \
  X(BindAPI, PFNEGLBINDAPIPROC)                     \
  X(ChooseConfig, PFNEGLCHOOSECONFIGPROC)           \
  X(CreateContext, PFNEGLCREATECONTEXTPROC)         \
  X(DestroyContext, PFNEGLDESTROYCONTEXTPROC)       \
  X(MakeCurrent, PFNEGLMAKECURRENTPROC)             \
  X(GetCurrentContext, PFNEGLGETCURRENTCONTEXTPROC)

/// A loaded libEGL with its entry points. Never unloaded (see egl_context.hpp).
struct EglLibrary {
  std::string name;
  void* handle = nullptr;
#define VPROXQ_EGL_DECLARE(name, type) type name = nullptr;
  VPROXQ_EGL_FUNCTIONS(VPROXQ_EGL_DECLARE)
#undef VPROXQ_EGL_DECLARE
  // Extension entry points; null when the extension is missing.
  PFNEGLGETPLATFORMDISPLAYEXTPROC GetPlatformDisplayEXT = nullptr;
  PFNEGLQUERYDEVICESEXTPROC QueryDevicesEXT = nullptr;
  PFNEGLQUERYDEVICESTRINGEXTPROC QueryDeviceStringEXT = nullptr;
  std::string client_extensions;  ///< eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS)
};

bool has_extension(const std::string& list, const char* name) {
  std::istringstream tokens(list);
  std::string token;
  while (tokens >> token) {
    if (token == name) return true;
  }
  return false;
}

/// "`call` failed: EGL_BAD_xxx (0x....)" with the pending EGL error.
std::string egl_failure(const EglLibrary& egl, const std::string& call) {
  return call + " failed: " + egl_error_name(egl.GetError());
}

std::string resolve_library_name(const ContextOptions& options, std::string* origin) {
  if (!options.egl_library.empty()) {
    *origin = "ContextOptions::egl_library";
    return options.egl_library;
  }
  const char* from_env = std::getenv(kEglLibraryEnvVar);
  if (from_env != nullptr && *from_env != '\0') {
    *origin = std::string("$") + kEglLibraryEnvVar;
    return from_env;
  }
  *origin = "default";
  return kDefaultEglLibrary;
}

/// Loads (once per name and process) the EGL library; null and `error` set on failure.
const EglLibrary* load_egl_library(const ContextOptions& options, std::string* error) {
  static std::mutex mutex;
  static std::map<std::string, std::unique_ptr<EglLibrary>> loaded;

  std::string origin;
  const std::string name = resolve_library_name(options, &origin);
  const std::lock_guard<std::mutex> lock(mutex);
  if (auto found = loaded.find(name); found != loaded.end()) return found->second.get();

  void* handle = dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    *error = "cannot load the EGL library '" + name + "' (" + origin +
             "): " + (why != nullptr ? why : "dlopen failed");
    return nullptr;
  }
  auto egl = std::make_unique<EglLibrary>();
  egl->name = name;
  egl->handle = handle;
#define VPROXQ_EGL_LOAD(fn, type)                                                      \
  egl->fn = reinterpret_cast<type>(dlsym(handle, "egl" #fn));                          \
  if (egl->fn == nullptr) {                                                            \
    *error = "the EGL library '" + name + "' has no symbol egl" #fn;                   \
    dlclose(handle);                                                                   \
    return nullptr;                                                                    \
  }
  VPROXQ_EGL_FUNCTIONS(VPROXQ_EGL_LOAD)
#undef VPROXQ_EGL_LOAD

  // Client extensions (EGL_EXT_client_extensions); a plain EGL 1.4 library returns null with
  // EGL_BAD_DISPLAY here, which only means that no platform extensions are available.
  const char* client = egl->QueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client != nullptr) {
    egl->client_extensions = client;
  } else {
    egl->GetError();
  }
  const std::string& ext = egl->client_extensions;
  if (has_extension(ext, "EGL_EXT_platform_base")) {
    egl->GetPlatformDisplayEXT = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        egl->GetProcAddress("eglGetPlatformDisplayEXT"));
  }
  if (has_extension(ext, "EGL_EXT_device_base") ||
      (has_extension(ext, "EGL_EXT_device_enumeration") &&
       has_extension(ext, "EGL_EXT_device_query"))) {
    egl->QueryDevicesEXT =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(egl->GetProcAddress("eglQueryDevicesEXT"));
    egl->QueryDeviceStringEXT = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        egl->GetProcAddress("eglQueryDeviceStringEXT"));
  }
  const EglLibrary* result = egl.get();
  loaded.emplace(name, std::move(egl));
  return result;
}

/// EGLDisplays are per process: two Contexts on the same device share one. eglTerminate is
/// called only when the last Context using a display goes away.
class DisplayRegistry {
 public:
  static void acquire(EGLDisplay display) {
    const std::lock_guard<std::mutex> lock(mutex());
    ++counts()[display];
  }
  static void release(const EglLibrary& egl, EGLDisplay display) {
    const std::lock_guard<std::mutex> lock(mutex());
    auto found = counts().find(display);
    if (found == counts().end()) return;
    if (--found->second == 0) {
      counts().erase(found);
      egl.Terminate(display);
    }
  }

 private:
  static std::mutex& mutex() {
    static std::mutex m;
    return m;
  }
  static std::map<EGLDisplay, int>& counts() {
    static std::map<EGLDisplay, int> c;
    return c;
  }
};

const char* device_string(const EglLibrary& egl, EGLDeviceEXT device, EGLint name) {
  const char* value = egl.QueryDeviceStringEXT(device, name);
  if (value == nullptr) egl.GetError();  // clear EGL_BAD_PARAMETER for unsupported names
  return value;
}

struct DeviceEnumeration {
  std::vector<EGLDeviceEXT> handles;
  std::vector<EglDevice> devices;
  std::string error;
};

DeviceEnumeration enumerate_devices(const EglLibrary& egl) {
  DeviceEnumeration out;
  if (egl.QueryDevicesEXT == nullptr || egl.QueryDeviceStringEXT == nullptr) {
    out.error = "the EGL library '" + egl.name +
                "' lacks EGL_EXT_device_enumeration/EGL_EXT_device_query";
    return out;
  }
  EGLint count = 0;
  if (egl.QueryDevicesEXT(0, nullptr, &count) != EGL_TRUE) {
    out.error = egl_failure(egl, "eglQueryDevicesEXT");
    return out;
  }
  out.handles.resize(static_cast<std::size_t>(count));
  if (count > 0 && egl.QueryDevicesEXT(count, out.handles.data(), &count) != EGL_TRUE) {
    out.error = egl_failure(egl, "eglQueryDevicesEXT");
    out.handles.clear();
    return out;
  }
  out.handles.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    EglDevice device;
    device.index = i;
    const EGLDeviceEXT handle = out.handles[static_cast<std::size_t>(i)];
    if (const char* ext = device_string(egl, handle, EGL_EXTENSIONS)) device.extensions = ext;
    device.software = has_extension(device.extensions, "EGL_MESA_device_software");
    if (has_extension(device.extensions, "EGL_EXT_device_drm")) {
      if (const char* file = device_string(egl, handle, EGL_DRM_DEVICE_FILE_EXT)) {
        device.drm_device_file = file;
      }
    }
    if (has_extension(device.extensions, "EGL_EXT_device_drm_render_node")) {
      if (const char* file = device_string(egl, handle, EGL_DRM_RENDER_NODE_FILE_EXT)) {
        device.drm_render_node = file;
      }
    }
    out.devices.push_back(std::move(device));
  }
  return out;
}

/// One display to try: a platform display (EGL_PLATFORM_*) or eglGetDisplay's default.
struct DisplayCandidate {
  std::string label;
  EGLenum platform = 0;  ///< 0: eglGetDisplay(EGL_DEFAULT_DISPLAY)
  void* native = nullptr;
  bool software_device = false;
};

bool looks_like_software_renderer(const std::string& renderer) {
  for (const char* name : {"llvmpipe", "softpipe", "SwiftShader", "Software Rasterizer"}) {
    if (renderer.find(name) != std::string::npos) return true;
  }
  return false;
}

std::string gl_string(const GlFunctions& gl, GLenum name, const char* label) {
  const GLubyte* value = gl.GetString(name);
  check_gl(gl, label);
  if (value == nullptr) throw GlError(std::string(label) + " returned NULL");
  return reinterpret_cast<const char*>(value);
}

GLint gl_integer(const GlFunctions& gl, GLenum name, const char* label) {
  GLint value = 0;
  gl.GetIntegerv(name, &value);
  check_gl(gl, label);
  return value;
}

}  // namespace

struct Context::Impl {
  const EglLibrary* egl = nullptr;
  EGLDisplay display = EGL_NO_DISPLAY;
  bool display_acquired = false;
  EGLContext context = EGL_NO_CONTEXT;
  GlFunctions gl;
  ContextInfo info;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    if (context != EGL_NO_CONTEXT) {
      if (egl->GetCurrentContext() == context) {
        egl->MakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      }
      egl->DestroyContext(display, context);
    }
    if (display_acquired) DisplayRegistry::release(*egl, display);
  }
};

struct ContextFactory {
  static Context make(std::unique_ptr<Context::Impl> impl) { return Context(std::move(impl)); }
};

Context::Context(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Context::Context(Context&&) noexcept = default;
Context& Context::operator=(Context&&) noexcept = default;
Context::~Context() = default;

std::string Context::renderer() const {
  return impl_->info.gl_renderer + "; OpenGL " + impl_->info.gl_version;
}
const ContextInfo& Context::info() const { return impl_->info; }
const GlFunctions& Context::gl() const { return impl_->gl; }

void Context::make_current() const {
  const EglLibrary& egl = *impl_->egl;
  if (egl.MakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl_->context) !=
      EGL_TRUE) {
    throw GlError(egl_failure(egl, "eglMakeCurrent"));
  }
}

void Context::release_current() const {
  const EglLibrary& egl = *impl_->egl;
  if (egl.MakeCurrent(impl_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT) !=
      EGL_TRUE) {
    throw GlError(egl_failure(egl, "eglMakeCurrent(EGL_NO_CONTEXT)"));
  }
}

namespace {

/// Creates a context on one display; null and `error` set on failure (everything made so
/// far is released by Impl's destructor).
std::unique_ptr<Context::Impl> try_display(const EglLibrary& egl, const DisplayCandidate& cand,
                                           const ContextOptions& options, std::string* error) {
  auto impl = std::make_unique<Context::Impl>();
  impl->egl = &egl;
  impl->info.egl_library = egl.name;
  impl->info.display = cand.label;

  if (cand.platform != 0) {
    impl->display = egl.GetPlatformDisplayEXT(cand.platform, cand.native, nullptr);
    if (impl->display == EGL_NO_DISPLAY) {
      *error = egl_failure(egl, "eglGetPlatformDisplayEXT");
      return nullptr;
    }
  } else {
    impl->display = egl.GetDisplay(EGL_DEFAULT_DISPLAY);
    if (impl->display == EGL_NO_DISPLAY) {
      *error = "eglGetDisplay(EGL_DEFAULT_DISPLAY) returned EGL_NO_DISPLAY";
      egl.GetError();
      return nullptr;
    }
  }
  EGLint egl_major = 0;
  EGLint egl_minor = 0;
  if (egl.Initialize(impl->display, &egl_major, &egl_minor) != EGL_TRUE) {
    *error = egl_failure(egl, "eglInitialize");
    return nullptr;
  }
  DisplayRegistry::acquire(impl->display);
  impl->display_acquired = true;
  impl->info.egl_version = std::to_string(egl_major) + "." + std::to_string(egl_minor);

  const char* display_ext_raw = egl.QueryString(impl->display, EGL_EXTENSIONS);
  if (display_ext_raw == nullptr) {
    *error = egl_failure(egl, "eglQueryString(EGL_EXTENSIONS)");
    return nullptr;
  }
  const std::string display_ext = display_ext_raw;
  const bool egl15 = egl_major > 1 || (egl_major == 1 && egl_minor >= 5);
  const bool khr_create_context = has_extension(display_ext, "EGL_KHR_create_context");
  if (!egl15 && !khr_create_context) {
    *error = "EGL " + impl->info.egl_version +
             " display lacks EGL_KHR_create_context (needed to ask for a core profile)";
    return nullptr;
  }
  if (!has_extension(display_ext, "EGL_KHR_surfaceless_context")) {
    *error = "the display lacks EGL_KHR_surfaceless_context";
    return nullptr;
  }
  if (egl.BindAPI(EGL_OPENGL_API) != EGL_TRUE) {
    *error = egl_failure(egl, "eglBindAPI(EGL_OPENGL_API)");
    return nullptr;
  }

  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!has_extension(display_ext, "EGL_KHR_no_config_context") &&
      !has_extension(display_ext, "EGL_MESA_configless_context")) {
    // No surface is ever made, so any surface type will do: EGL_SURFACE_TYPE is a mask
    // attribute, and 0 asks for no bit.
    const EGLint config_attribs[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                     EGL_NONE};
    EGLint config_count = 0;
    if (egl.ChooseConfig(impl->display, config_attribs, &config, 1, &config_count) != EGL_TRUE) {
      *error = egl_failure(egl, "eglChooseConfig");
      return nullptr;
    }
    if (config_count == 0) {
      *error = "eglChooseConfig found no config with EGL_OPENGL_BIT";
      return nullptr;
    }
  }

  std::vector<EGLint> context_attribs = {
      EGL_CONTEXT_MAJOR_VERSION_KHR, options.gl_major,
      EGL_CONTEXT_MINOR_VERSION_KHR, options.gl_minor,
      EGL_CONTEXT_OPENGL_PROFILE_MASK_KHR, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT_KHR};
  if (options.debug) {
    if (khr_create_context) {
      context_attribs.insert(context_attribs.end(),
                             {EGL_CONTEXT_FLAGS_KHR, EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR});
    } else {
      context_attribs.insert(context_attribs.end(), {EGL_CONTEXT_OPENGL_DEBUG, EGL_TRUE});
    }
  }
  context_attribs.push_back(EGL_NONE);
  impl->context =
      egl.CreateContext(impl->display, config, EGL_NO_CONTEXT, context_attribs.data());
  if (impl->context == EGL_NO_CONTEXT) {
    *error = egl_failure(egl, "eglCreateContext(OpenGL " + std::to_string(options.gl_major) +
                                  "." + std::to_string(options.gl_minor) + " core profile)");
    return nullptr;
  }
  if (egl.MakeCurrent(impl->display, EGL_NO_SURFACE, EGL_NO_SURFACE, impl->context) !=
      EGL_TRUE) {
    *error = egl_failure(egl, "eglMakeCurrent(EGL_NO_SURFACE)");
    return nullptr;
  }

  GlFunctions& gl = impl->gl;
#define VPROXQ_GL_LOAD(fn, type)                                                     \
  gl.fn = reinterpret_cast<type>(egl.GetProcAddress("gl" #fn));                      \
  if (gl.fn == nullptr) {                                                            \
    *error = "eglGetProcAddress(\"gl" #fn "\") returned NULL";                       \
    return nullptr;                                                                  \
  }
  VPROXQ_GL_FUNCTIONS(VPROXQ_GL_LOAD)
#undef VPROXQ_GL_LOAD

  try {
    ContextInfo& info = impl->info;
    gl.GetError();  // a fresh context has no error set; this only guards against drivers
    info.gl_vendor = gl_string(gl, GL_VENDOR, "glGetString(GL_VENDOR)");
    info.gl_renderer = gl_string(gl, GL_RENDERER, "glGetString(GL_RENDERER)");
    info.gl_version = gl_string(gl, GL_VERSION, "glGetString(GL_VERSION)");
    info.gl_major = gl_integer(gl, GL_MAJOR_VERSION, "glGetIntegerv(GL_MAJOR_VERSION)");
    info.gl_minor = gl_integer(gl, GL_MINOR_VERSION, "glGetIntegerv(GL_MINOR_VERSION)");
    if (info.gl_major < options.gl_major ||
        (info.gl_major == options.gl_major && info.gl_minor < options.gl_minor)) {
      *error = "got OpenGL " + std::to_string(info.gl_major) + "." +
               std::to_string(info.gl_minor) + " (" + info.gl_renderer + "), need " +
               std::to_string(options.gl_major) + "." + std::to_string(options.gl_minor);
      return nullptr;
    }
    info.core_profile = (gl_integer(gl, GL_CONTEXT_PROFILE_MASK,
                                    "glGetIntegerv(GL_CONTEXT_PROFILE_MASK)") &
                         GL_CONTEXT_CORE_PROFILE_BIT) != 0;
    info.software = cand.software_device || looks_like_software_renderer(info.gl_renderer);
    GLint64 block_size = 0;
    gl.GetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &block_size);
    check_gl(gl, "glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE)");
    info.max_ssbo_block_size = block_size;
    info.max_ssbo_bindings = gl_integer(gl, GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS,
                                        "glGetIntegerv(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS)");
    info.max_work_group_invocations =
        gl_integer(gl, GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS,
                   "glGetIntegerv(GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS)");
    for (GLuint axis = 0; axis < 3; ++axis) {
      gl.GetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT, axis, &info.max_work_group_count[axis]);
      check_gl(gl, "glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_COUNT)");
      gl.GetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_SIZE, axis, &info.max_work_group_size[axis]);
      check_gl(gl, "glGetIntegeri_v(GL_MAX_COMPUTE_WORK_GROUP_SIZE)");
    }
  } catch (const GlError& e) {
    *error = e.what();
    return nullptr;
  }
  return impl;
}

std::string device_label(const EglDevice& device) { return "EGL device " + device.description(); }

}  // namespace

std::string EglDevice::description() const {
  std::string out = std::to_string(index) + (software ? ": software device" : ": hardware device");
  if (!drm_render_node.empty()) {
    out += " " + drm_render_node;
  } else if (!drm_device_file.empty()) {
    out += " " + drm_device_file;
  } else if (software) {
    out += " (EGL_MESA_device_software)";
  }
  if (!renderer.empty()) out += ", " + renderer;
  return out;
}

ContextResult try_create_context(const ContextOptions& options) {
  ContextResult result;
  const std::string wanted = "no OpenGL " + std::to_string(options.gl_major) + "." +
                             std::to_string(options.gl_minor) + " core context";
  std::string load_error;
  const EglLibrary* egl = load_egl_library(options, &load_error);
  if (egl == nullptr) {
    result.error = wanted + ": " + load_error;
    return result;
  }

  std::vector<DisplayCandidate> candidates;
  std::vector<std::string> failures;
  const bool platform_base = egl->GetPlatformDisplayEXT != nullptr;
  const bool platform_device =
      platform_base && has_extension(egl->client_extensions, "EGL_EXT_platform_device");
  DeviceEnumeration enumeration;
  if (platform_device) enumeration = enumerate_devices(*egl);

  if (options.device_index >= 0) {
    if (!platform_device) {
      result.error = wanted + ": device " + std::to_string(options.device_index) +
                     " was asked for, but the EGL library '" + egl->name +
                     "' lacks EGL_EXT_platform_device";
      return result;
    }
    if (!enumeration.error.empty()) {
      result.error = wanted + ": " + enumeration.error;
      return result;
    }
    const auto index = static_cast<std::size_t>(options.device_index);
    if (index >= enumeration.devices.size()) {
      std::string found;
      for (const EglDevice& device : enumeration.devices) {
        found += (found.empty() ? "" : ", ") + device.description();
      }
      result.error = wanted + ": EGL device " + std::to_string(options.device_index) +
                     " does not exist; " + std::to_string(enumeration.devices.size()) +
                     " found" + (found.empty() ? "" : " (" + found + ")");
      return result;
    }
    const EglDevice& device = enumeration.devices[index];
    candidates.push_back({device_label(device), EGL_PLATFORM_DEVICE_EXT,
                          enumeration.handles[index], device.software});
  } else {
    const EglPlatform platform = options.platform;
    const bool automatic = platform == EglPlatform::Automatic;
    if (automatic || platform == EglPlatform::Device) {
      if (!platform_device) {
        failures.push_back("EGL_EXT_platform_device: not supported by the EGL library");
      } else if (!enumeration.error.empty()) {
        failures.push_back("EGL_EXT_platform_device: " + enumeration.error);
      } else if (enumeration.devices.empty()) {
        failures.push_back("EGL_EXT_platform_device: eglQueryDevicesEXT found no device");
      }
      // Hardware devices first, in enumeration order, then software ones.
      for (const bool software : {false, true}) {
        for (const EglDevice& device : enumeration.devices) {
          if (device.software != software) continue;
          candidates.push_back({device_label(device), EGL_PLATFORM_DEVICE_EXT,
                                enumeration.handles[static_cast<std::size_t>(device.index)],
                                device.software});
        }
      }
    }
    if (automatic || platform == EglPlatform::Surfaceless) {
      if (platform_base &&
          has_extension(egl->client_extensions, "EGL_MESA_platform_surfaceless")) {
        candidates.push_back({"EGL_MESA_platform_surfaceless", EGL_PLATFORM_SURFACELESS_MESA,
                              EGL_DEFAULT_DISPLAY, false});
      } else {
        failures.push_back("EGL_MESA_platform_surfaceless: not supported by the EGL library");
      }
    }
    if (automatic || platform == EglPlatform::DefaultDisplay) {
      candidates.push_back({"EGL_DEFAULT_DISPLAY", 0, nullptr, false});
    }
  }

  for (const DisplayCandidate& candidate : candidates) {
    std::string error;
    std::unique_ptr<Context::Impl> impl = try_display(*egl, candidate, options, &error);
    if (impl) {
      result.context.emplace(ContextFactory::make(std::move(impl)));
      return result;
    }
    failures.push_back(candidate.label + ": " + error);
  }
  result.error = wanted + " (EGL library '" + egl->name + "')";
  for (std::size_t i = 0; i < failures.size(); ++i) {
    result.error += (i == 0 ? ": " : "; ") + failures[i];
  }
  return result;
}

Context create_context(const ContextOptions& options) {
  ContextResult result = try_create_context(options);
  if (!result) throw RuntimeError(result.error);
  return std::move(*result.context);
}

DeviceListResult list_devices(const ContextOptions& options, bool probe_renderer) {
  DeviceListResult result;
  const EglLibrary* egl = load_egl_library(options, &result.error);
  if (egl == nullptr) return result;
  if (egl->GetPlatformDisplayEXT == nullptr ||
      !has_extension(egl->client_extensions, "EGL_EXT_platform_device")) {
    result.error = "the EGL library '" + egl->name + "' lacks EGL_EXT_platform_device";
    return result;
  }
  DeviceEnumeration enumeration = enumerate_devices(*egl);
  result.error = enumeration.error;
  result.devices = std::move(enumeration.devices);
  if (probe_renderer) {
    for (EglDevice& device : result.devices) {
      ContextOptions probe = options;
      probe.device_index = device.index;
      ContextResult context = try_create_context(probe);
      device.renderer = context ? context.context->renderer() : "unavailable: " + context.error;
    }
  }
  return result;
}

}  // namespace vproxq::gl
