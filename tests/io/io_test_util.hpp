#pragma once
// Helpers for the io/ tests: a self-cleaning temporary folder, binary PLY building, and a
// check that a call throws InputError whose message contains given phrases.
#include "core/errors.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>
#include <utility>

#include <unistd.h>

namespace vproxq::test {

namespace fs = std::filesystem;

/// A fresh folder under the system temp folder, removed with everything in it at scope exit.
class TempDir {
 public:
  TempDir() {
    static std::atomic<int> counter{0};
    std::random_device rd;
    path_ = fs::temp_directory_path() / ("vproxq-io-test-" + std::to_string(::getpid()) + "-" +
                                         std::to_string(counter++) + "-" + std::to_string(rd()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const fs::path& path() const { return path_; }

  /// Writes `bytes` to `relative` (creating folders) and returns the full path.
  fs::path write(const std::string& relative, const std::string& bytes) const {
    const fs::path p = path_ / relative;
    if (p.has_parent_path()) fs::create_directories(p.parent_path());
    std::ofstream out(p, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return p;
  }

 private:
  fs::path path_;
};

/// Appends `v` to `out` in little or big endian byte order.
template <class T>
void put(std::string& out, T v, bool big_endian) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, &v, sizeof(T));
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  const bool host_little = first == 1;
  if (host_little == big_endian) {
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
  }
  out.append(reinterpret_cast<const char*>(raw), sizeof(T));
}

/// The message of the InputError `f` throws; a test failure if it throws none.
template <class F>
std::string input_error_message(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError, none was thrown";
  return {};
}

inline void expect_contains_all(const std::string& message,
                                std::initializer_list<std::string> phrases) {
  for (const std::string& p : phrases) {
    EXPECT_NE(message.find(p), std::string::npos) << "message: " << message << "\n  lacks: " << p;
  }
}

}  // namespace vproxq::test

/// Checks that `statement` throws vproxq::InputError and that its message contains every one
/// of the phrases that follow (strings).
#define EXPECT_INPUT_ERROR(statement, ...)                                               \
  do {                                                                                   \
    SCOPED_TRACE(#statement);                                                            \
    ::vproxq::test::expect_contains_all(                                                 \
        ::vproxq::test::input_error_message([&] { (void)(statement); }), {__VA_ARGS__}); \
  } while (0)
