#pragma once
// Shared by the benchmark harnesses in bench/: the --frames range, writing a result file so
// that a reader never sees half of it, and main()'s error handling with vproxq's exit codes.
#include "core/errors.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <string>
#include <utility>

namespace vproxq::bench {

/// Parses --frames ("A:B" = A..B-1, "A:", ":B", "A", or empty for all) into [first, last)
/// within [0, count). Throws UsageError.
inline std::pair<std::size_t, std::size_t> frame_range(const std::string& spec,
                                                       std::size_t count) {
  if (spec.empty()) return {0, count};
  auto number = [&](const std::string& s, std::size_t fallback) -> std::size_t {
    if (s.empty()) return fallback;
    if (s.find_first_not_of("0123456789") != std::string::npos)
      throw UsageError("--frames: '" + spec + "' is not A:B, A: , :B or A");
    return static_cast<std::size_t>(std::stoull(s));
  };
  const auto colon = spec.find(':');
  std::size_t first = 0, last = 0;
  if (colon == std::string::npos) {
    first = number(spec, 0);
    last = first + 1;
  } else {
    first = number(spec.substr(0, colon), 0);
    last = number(spec.substr(colon + 1), count);
  }
  if (first >= last || last > count)
    throw UsageError("--frames " + spec + ": the scene has frames 0.." +
                     std::to_string(count - 1) + " (A:B means A..B-1)");
  return {first, last};
}

/// Writes `text` to `path` through `path`.tmp and a rename. Throws RuntimeError.
inline void write_file_atomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f || std::fwrite(text.data(), 1, text.size(), f) != text.size() || std::fclose(f) != 0)
    throw RuntimeError("cannot write " + tmp);
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw RuntimeError("cannot rename " + tmp + " to " + path);
}

/// Parses the command line and runs `run()`, mapping errors to vproxq's exit codes with a
/// one-line message prefixed by the tool's name.
template <typename Run>
int guarded_main(const char* tool, CLI::App& app, int argc, char** argv, const Run& run) {
  auto fail = [&](const std::exception& e, int code) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return code;
  };
  try {
    app.parse(argc, argv);
    return run();
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : exit_code::kUsage;
  } catch (const UsageError& e) {
    return fail(e, exit_code::kUsage);
  } catch (const InputError& e) {
    return fail(e, exit_code::kInput);
  } catch (const std::exception& e) {
    return fail(e, exit_code::kRuntime);
  }
}

}  // namespace vproxq::bench
