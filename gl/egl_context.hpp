#pragma once
// Headless OpenGL 4.3+ core context through EGL, without a window system.
//
// libEGL is not linked: it is loaded with dlopen on the first try_create_context() call, so a
// vproxq binary starts on machines without any EGL/GL library and the caller can fall back
// to the CPU backend. Displays are tried in this order (automatic mode):
//   1. EGL_EXT_platform_device: every device eglQueryDevicesEXT reports, hardware devices
//      before software ones (EGL_MESA_device_software, e.g. llvmpipe);
//   2. EGL_MESA_platform_surfaceless;
//   3. eglGetDisplay(EGL_DEFAULT_DISPLAY).
// The first display on which a context can be created and made current wins. The context is
// current on the creating thread, with no surface (EGL_KHR_surfaceless_context).
#include "gl/gl_api.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vproxq::gl {

/// Name of the environment variable that overrides the EGL library loaded with dlopen.
inline constexpr const char* kEglLibraryEnvVar = "VPROXQ_EGL_LIBRARY";
/// Library loaded when neither ContextOptions::egl_library nor $VPROXQ_EGL_LIBRARY is set.
inline constexpr const char* kDefaultEglLibrary = "libEGL.so.1";

/// Which EGL display try_create_context() uses.
enum class EglPlatform {
  Automatic,       ///< devices (hardware first), then surfaceless, then the default display
  Device,          ///< EGL_EXT_platform_device only (all devices, or ContextOptions::device_index)
  Surfaceless,     ///< EGL_MESA_platform_surfaceless only
  DefaultDisplay,  ///< eglGetDisplay(EGL_DEFAULT_DISPLAY) only (honours $EGL_PLATFORM on Mesa)
};

struct ContextOptions {
  /// -1: any device (see `platform`). >= 0: only EGL_EXT_platform_device device number
  /// `device_index` (as listed by list_devices()) is tried, whatever `platform` says; no
  /// fallback to other displays.
  int device_index = -1;
  EglPlatform platform = EglPlatform::Automatic;
  /// dlopen name or path of libEGL; empty: $VPROXQ_EGL_LIBRARY, else kDefaultEglLibrary.
  std::string egl_library;
  /// Minimum OpenGL version of the core-profile context (compute shaders need 4.3).
  int gl_major = 4;
  int gl_minor = 3;
  /// Request a debug context (EGL_CONTEXT_OPENGL_DEBUG_BIT_KHR). Slower; for development.
  bool debug = false;
};

/// What is known about the GL implementation behind a context.
struct ContextInfo {
  std::string gl_vendor;    ///< GL_VENDOR, e.g. "Mesa"
  std::string gl_renderer;  ///< GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  std::string gl_version;   ///< GL_VERSION, e.g. "4.5 (Core Profile) Mesa 22.3.6"
  int gl_major = 0;         ///< GL_MAJOR_VERSION
  int gl_minor = 0;         ///< GL_MINOR_VERSION
  /// GL_CONTEXT_PROFILE_MASK has GL_CONTEXT_CORE_PROFILE_BIT (GL_VERSION says so only on
  /// some drivers: Mesa writes "(Core Profile)", NVIDIA does not).
  bool core_profile = false;
  std::string egl_library;  ///< the library that was loaded
  std::string egl_version;  ///< EGL_VERSION of the display, e.g. "1.5"
  /// Which display was used: "EGL device 0: software device (EGL_MESA_device_software)",
  /// "EGL_MESA_platform_surfaceless" or "EGL_DEFAULT_DISPLAY".
  std::string display;
  /// A CPU rasterizer (llvmpipe, softpipe, SwiftShader, ...): judged from the EGL device's
  /// EGL_MESA_device_software extension or, failing that, from the renderer string.
  bool software = false;
  // Compute limits, queried once at creation.
  std::int64_t max_ssbo_block_size = 0;          ///< GL_MAX_SHADER_STORAGE_BLOCK_SIZE, bytes
  int max_ssbo_bindings = 0;                     ///< GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS
  int max_work_group_count[3] = {0, 0, 0};       ///< GL_MAX_COMPUTE_WORK_GROUP_COUNT
  int max_work_group_size[3] = {0, 0, 0};        ///< GL_MAX_COMPUTE_WORK_GROUP_SIZE
  int max_work_group_invocations = 0;            ///< GL_MAX_COMPUTE_WORK_GROUP_INVOCATIONS
};

/// An EGL context made current on the creating thread (creating a Context makes it the
/// current one; call make_current() to switch back to another). Move-only; the destructor releases
/// and destroys the context (and terminates the display when no other Context uses it).
/// GL objects (ComputeProgram, StorageBuffer, ...) must be destroyed before their Context.
/// libEGL itself stays loaded until the process exits (unloading Mesa drivers is unsafe).
class Context {
 public:
  Context(Context&&) noexcept;
  Context& operator=(Context&&) noexcept;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context();

  /// "GL_RENDERER; OpenGL GL_VERSION", e.g.
  /// "llvmpipe (LLVM 15.0.6, 256 bits); OpenGL 4.5 (Core Profile) Mesa 22.3.6".
  /// Meant for logs and for the "device" field of results.json.
  std::string renderer() const;
  const ContextInfo& info() const;
  /// The GL function table; valid while this Context lives.
  const GlFunctions& gl() const;

  /// Makes the context current on the calling thread (it is current on the creating thread
  /// already). Throws GlError naming eglMakeCurrent and the EGL error on failure.
  void make_current() const;
  /// Releases the context from the calling thread so that another thread can make it current.
  void release_current() const;

  struct Impl;

 private:
  explicit Context(std::unique_ptr<Impl> impl);
  friend struct ContextFactory;
  std::unique_ptr<Impl> impl_;
};

/// Result of try_create_context(): a context, or why none could be made.
struct ContextResult {
  std::optional<Context> context;
  /// Empty on success. Otherwise one line naming the failed calls with decoded errors, for
  /// every display tried, e.g. "no OpenGL 4.3 core context: EGL_MESA_platform_surfaceless:
  /// eglInitialize failed: EGL_NOT_INITIALIZED (0x3001); ...".
  std::string error;
  explicit operator bool() const { return context.has_value(); }
};

/// Creates a headless context and makes it current on the calling thread. Never throws for
/// an unavailable EGL/GL (missing library, no device, too old GL, ...): the failure is
/// reported in ContextResult::error so that the caller can fall back to the CPU backend.
/// After a failure no context may be current on the calling thread.
ContextResult try_create_context(const ContextOptions& options = {});

/// try_create_context(), throwing RuntimeError with the failure message. For --voronoi=gpu.
Context create_context(const ContextOptions& options = {});

/// An EGL device (EGL_EXT_device_enumeration), in the order of eglQueryDevicesEXT: its index
/// is the ContextOptions::device_index that selects it.
struct EglDevice {
  int index = 0;
  bool software = false;         ///< advertises EGL_MESA_device_software
  std::string drm_device_file;   ///< EGL_DRM_DEVICE_FILE_EXT, e.g. "/dev/dri/card0"; may be empty
  std::string drm_render_node;   ///< EGL_DRM_RENDER_NODE_FILE_EXT, e.g. "/dev/dri/renderD128"
  std::string extensions;        ///< the device's extension string
  /// GL_RENDERER of a context made on this device; filled only when list_devices() was asked
  /// to probe, else empty. Holds the failure message when probing failed.
  std::string renderer;
  /// One line for `--device` listings: "1: hardware device /dev/dri/renderD128" or
  /// "0: software device (EGL_MESA_device_software)", then ", <renderer>" when probed.
  std::string description() const;
};

struct DeviceListResult {
  std::vector<EglDevice> devices;
  std::string error;  ///< empty on success (an empty device list is not an error)
};

/// Devices found through EGL_EXT_device_enumeration. With `probe_renderer`, a context is made
/// on each device in turn to fill EglDevice::renderer (slower: one context per device).
/// Uses options.egl_library; the other options apply to probing only.
DeviceListResult list_devices(const ContextOptions& options = {}, bool probe_renderer = false);

/// "EGL_BAD_ALLOC (0x3003)" and so on; unknown codes as "unknown EGL error 0x1234".
std::string egl_error_name(std::int32_t error);

}  // namespace vproxq::gl
