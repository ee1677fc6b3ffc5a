// The headless EGL context: creation, reported capabilities, failure reporting, lifetime.
#include "gl/egl_context.hpp"
#include "gl_test_support.hpp"

#include <gtest/gtest.h>

#include <elf.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace vproxq::gl {
namespace {

/// Sets an environment variable for the lifetime of the object and restores it afterwards.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = std::string(old);
    setenv(name, value, 1);
  }
  ~ScopedEnv() {
    if (old_) {
      setenv(name_, old_->c_str(), 1);
    } else {
      unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST(GlContext, CreatesOpenGl43CoreContext) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const ContextInfo& info = context.info();
  EXPECT_TRUE(info.gl_major > 4 || (info.gl_major == 4 && info.gl_minor >= 3))
      << "GL " << info.gl_major << "." << info.gl_minor;
  EXPECT_FALSE(info.gl_renderer.empty());
  EXPECT_FALSE(info.gl_version.empty());
  // From GL_CONTEXT_PROFILE_MASK: GL_VERSION names the profile on Mesa only (NVIDIA's reads
  // "4.3.0 NVIDIA 580.159.04").
  EXPECT_TRUE(info.core_profile) << info.gl_version;
  if (info.gl_vendor == "Mesa") {
    EXPECT_NE(info.gl_version.find("Core Profile"), std::string::npos) << info.gl_version;
  }
  const std::string renderer = context.renderer();
  EXPECT_NE(renderer.find(info.gl_renderer), std::string::npos);
  EXPECT_NE(renderer.find(info.gl_version), std::string::npos);
  EXPECT_EQ(renderer.find('\n'), std::string::npos);
  std::cout << "renderer: " << renderer << "\ndisplay:  " << info.display << " (EGL "
            << info.egl_version << ", " << info.egl_library << ")"
            << (info.software ? ", software" : ", hardware") << "\n";
  RecordProperty("renderer", renderer);
  RecordProperty("display", info.display);
}

TEST(GlContext, ReportsComputeLimitsAtLeastTheGl43Minimums) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const ContextInfo& info = context.info();
  // Minimum values required by the OpenGL 4.3 core specification (table 23.64).
  EXPECT_GE(info.max_ssbo_block_size, std::int64_t{1} << 24);
  EXPECT_GE(info.max_ssbo_bindings, 8);
  EXPECT_GE(info.max_work_group_invocations, 1024);
  for (int axis = 0; axis < 3; ++axis) EXPECT_GE(info.max_work_group_count[axis], 65535);
  EXPECT_GE(info.max_work_group_size[0], 1024);
  EXPECT_GE(info.max_work_group_size[2], 64);
}

TEST(GlContext, MissingEglLibraryFailsCleanlyNamingTheLibrary) {
  constexpr const char* kMissing = "libvproxq-no-such-egl.so.7";
  {
    const ScopedEnv env(kEglLibraryEnvVar, kMissing);
    const ContextResult result = try_create_context();
    ASSERT_FALSE(result);
    EXPECT_NE(result.error.find(kMissing), std::string::npos) << result.error;
    EXPECT_NE(result.error.find(kEglLibraryEnvVar), std::string::npos) << result.error;
    EXPECT_EQ(result.error.find('\n'), std::string::npos) << "one line: " << result.error;
    try {
      create_context();
      ADD_FAILURE() << "create_context() did not throw";
    } catch (const RuntimeError& e) {
      EXPECT_NE(std::string(e.what()).find(kMissing), std::string::npos) << e.what();
    }
    const DeviceListResult devices = list_devices();
    EXPECT_TRUE(devices.devices.empty());
    EXPECT_NE(devices.error.find(kMissing), std::string::npos) << devices.error;
  }
  ContextOptions options;
  options.egl_library = kMissing;
  const ContextResult result = try_create_context(options);
  ASSERT_FALSE(result);
  EXPECT_NE(result.error.find(kMissing), std::string::npos) << result.error;
}

/// The DT_NEEDED entries of an ELF64 file: the shared libraries it is linked against.
std::vector<std::string> needed_libraries(const char* path) {
  std::ifstream file(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(file)),
                                std::istreambuf_iterator<char>());
  std::vector<std::string> needed;
  if (bytes.size() < sizeof(Elf64_Ehdr)) return needed;
  Elf64_Ehdr header;
  std::memcpy(&header, bytes.data(), sizeof header);
  auto program_header = [&](int i) {
    Elf64_Phdr ph;
    std::memcpy(&ph, bytes.data() + header.e_phoff + i * header.e_phentsize, sizeof ph);
    return ph;
  };
  // File offset of a virtual address, through the PT_LOAD segments.
  auto offset_of = [&](Elf64_Addr address) -> std::size_t {
    for (int i = 0; i < header.e_phnum; ++i) {
      const Elf64_Phdr ph = program_header(i);
      if (ph.p_type == PT_LOAD && address >= ph.p_vaddr && address < ph.p_vaddr + ph.p_filesz) {
        return ph.p_offset + (address - ph.p_vaddr);
      }
    }
    return 0;
  };
  for (int i = 0; i < header.e_phnum; ++i) {
    const Elf64_Phdr ph = program_header(i);
    if (ph.p_type != PT_DYNAMIC) continue;
    std::vector<Elf64_Dyn> entries(ph.p_filesz / sizeof(Elf64_Dyn));
    std::memcpy(entries.data(), bytes.data() + ph.p_offset, entries.size() * sizeof(Elf64_Dyn));
    std::size_t strtab = 0;
    for (const Elf64_Dyn& entry : entries) {
      if (entry.d_tag == DT_STRTAB) strtab = offset_of(entry.d_un.d_ptr);
    }
    for (const Elf64_Dyn& entry : entries) {
      if (entry.d_tag == DT_NEEDED) needed.emplace_back(bytes.data() + strtab + entry.d_un.d_val);
    }
  }
  return needed;
}

TEST(GlContext, BinaryDoesNotLinkEglOrGl) {
  // vproxq::gl is static and loads libEGL with dlopen: an executable linking it (this one,
  // like vproxq) must start on machines without EGL/GL libraries.
  const std::vector<std::string> needed = needed_libraries("/proc/self/exe");
  ASSERT_FALSE(needed.empty()) << "could not read the dynamic section of /proc/self/exe";
  for (const std::string& library : needed) {
    for (const char* forbidden : {"libEGL", "libGL", "libOpenGL", "libGLX", "libgbm"}) {
      EXPECT_NE(library.rfind(forbidden, 0), 0u) << "linked against " << library;
    }
  }
}

TEST(GlContext, NonexistentDeviceIndexFailsWithTheIndex) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);  // with EGL working, only the index can be the problem
  (void)context;
  ContextOptions options;
  options.device_index = 4711;
  const ContextResult result = try_create_context(options);
  ASSERT_FALSE(result);
  EXPECT_NE(result.error.find("4711"), std::string::npos) << result.error;
}

TEST(GlContext, UnsupportedVersionNamesTheEglCallAndError) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);  // GL works here: the failure below is the version's
  (void)context;
  ContextOptions options;
  options.gl_major = 9;
  options.gl_minor = 9;
  const ContextResult result = try_create_context(options);
  ASSERT_FALSE(result);
  EXPECT_NE(result.error.find("eglCreateContext"), std::string::npos) << result.error;
  EXPECT_NE(result.error.find("EGL_BAD_"), std::string::npos) << result.error;
  EXPECT_NE(result.error.find("OpenGL 9.9"), std::string::npos) << result.error;
  std::cout << "expected failure: " << result.error << "\n";
}

TEST(GlContext, ContextsCoexistAndCleanUp) {
  VPROXQ_GL_CONTEXT_OR_FAIL(shared);
  // Same display as the shared context: destroying these must not terminate it.
  for (int round = 0; round < 3; ++round) {
    ContextResult a = try_create_context();
    ContextResult b = try_create_context();
    ASSERT_TRUE(a) << a.error;
    ASSERT_TRUE(b) << b.error;
    a.context->make_current();
    EXPECT_EQ(a.context->gl().GetError(), static_cast<GLenum>(GL_NO_ERROR));
    EXPECT_NE(a.context->gl().GetString(GL_RENDERER), nullptr);
    Context moved = std::move(*b.context);
    moved.make_current();
    EXPECT_NE(moved.gl().GetString(GL_VERSION), nullptr);
  }
  shared.make_current();
  EXPECT_NE(shared.gl().GetString(GL_RENDERER), nullptr);
  EXPECT_EQ(shared.gl().GetError(), static_cast<GLenum>(GL_NO_ERROR));
}

TEST(GlContext, EachPlatformCanBeChosen) {
  VPROXQ_GL_CONTEXT_OR_FAIL(shared);
  // Mesa (what CI runs) supports both the device and the surfaceless platform, with or
  // without $EGL_PLATFORM; other drivers may lack one, and then the error must say which.
  const bool mesa = shared.info().gl_version.find("Mesa") != std::string::npos;
  const struct {
    EglPlatform platform;
    const char* name;
  } platforms[] = {{EglPlatform::Device, "EGL device"},
                   {EglPlatform::Surfaceless, "EGL_MESA_platform_surfaceless"}};
  for (const auto& each : platforms) {
    ContextOptions options;
    options.platform = each.platform;
    const ContextResult result = try_create_context(options);
    if (result) {
      EXPECT_EQ(result.context->info().display.rfind(each.name, 0), 0u)
          << result.context->info().display;
      std::cout << each.name << ": " << result.context->renderer() << "\n";
    } else {
      EXPECT_FALSE(mesa) << result.error;
      EXPECT_NE(result.error.find(each.name), std::string::npos) << result.error;
    }
  }
  shared.make_current();
}

TEST(GlContext, CanMoveToAnotherThread) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  context.release_current();
  std::string renderer;
  std::string error;
  std::thread worker([&] {
    try {
      context.make_current();
      const GLubyte* value = context.gl().GetString(GL_RENDERER);
      check_gl(context.gl(), "glGetString(GL_RENDERER)");
      if (value != nullptr) renderer = reinterpret_cast<const char*>(value);
      context.release_current();
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  worker.join();
  context.make_current();
  EXPECT_TRUE(error.empty()) << error;
  EXPECT_EQ(renderer, context.info().gl_renderer);
}

TEST(GlContext, ListsDevices) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const DeviceListResult list = list_devices({}, /*probe_renderer=*/true);
  context.make_current();  // probing made and destroyed other contexts
  if (!list.error.empty()) {
    // Only acceptable when the EGL library has no device platform at all.
    EXPECT_NE(list.error.find("EGL_EXT_platform_device"), std::string::npos) << list.error;
  }
  for (std::size_t i = 0; i < list.devices.size(); ++i) {
    const EglDevice& device = list.devices[i];
    EXPECT_EQ(device.index, static_cast<int>(i));
    EXPECT_FALSE(device.renderer.empty());
    std::cout << "device " << device.description() << "\n";
  }
}

TEST(GlErrors, EglErrorsAreDecodedByName) {
  EXPECT_EQ(egl_error_name(0x3000), "EGL_SUCCESS (0x3000)");
  EXPECT_EQ(egl_error_name(0x3001), "EGL_NOT_INITIALIZED (0x3001)");
  EXPECT_EQ(egl_error_name(0x3003), "EGL_BAD_ALLOC (0x3003)");
  EXPECT_EQ(egl_error_name(0x3008), "EGL_BAD_DISPLAY (0x3008)");
  EXPECT_EQ(egl_error_name(0x3009), "EGL_BAD_MATCH (0x3009)");
  EXPECT_EQ(egl_error_name(0x300E), "EGL_CONTEXT_LOST (0x300E)");
  EXPECT_EQ(egl_error_name(0x322B), "EGL_BAD_DEVICE_EXT (0x322B)");
  EXPECT_EQ(egl_error_name(0x1234), "unknown EGL error 0x1234");
  for (std::int32_t code = 0x3000; code <= 0x300E; ++code) {
    EXPECT_EQ(egl_error_name(code).rfind("EGL_", 0), 0u) << code;
  }
}

TEST(GlErrors, GlErrorsAreDecodedByName) {
  EXPECT_EQ(gl_error_name(GL_NO_ERROR), "GL_NO_ERROR");
  EXPECT_EQ(gl_error_name(GL_INVALID_ENUM), "GL_INVALID_ENUM");
  EXPECT_EQ(gl_error_name(GL_INVALID_VALUE), "GL_INVALID_VALUE");
  EXPECT_EQ(gl_error_name(GL_INVALID_OPERATION), "GL_INVALID_OPERATION");
  EXPECT_EQ(gl_error_name(GL_OUT_OF_MEMORY), "GL_OUT_OF_MEMORY");
  EXPECT_EQ(gl_error_name(GL_INVALID_FRAMEBUFFER_OPERATION), "GL_INVALID_FRAMEBUFFER_OPERATION");
  EXPECT_EQ(gl_error_name(GL_CONTEXT_LOST), "GL_CONTEXT_LOST");
  EXPECT_EQ(gl_error_name(0xBEEF), "unknown GL error 0xBEEF");
}

TEST(GlErrors, FailedGlCallIsReportedWithCallAndError) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const GlFunctions& gl = context.gl();
  constexpr GLenum kNotABufferTarget = 0xDEAD;
  gl.BindBuffer(kNotABufferTarget, 0);
  try {
    check_gl(gl, "glBindBuffer");
    ADD_FAILURE() << "check_gl did not throw";
  } catch (const GlError& e) {
    EXPECT_STREQ(e.what(), "glBindBuffer failed: GL_INVALID_ENUM");
  }
  EXPECT_NO_THROW(check_gl(gl, "nothing"));  // the flag was drained
}

}  // namespace
}  // namespace vproxq::gl
