#include "trap_on_test_failure.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace vproxq::fuzz {

namespace {

/// Stops the process at the first failed GoogleTest assertion (they also report outside a
/// running test), so that libFuzzer records the input.
class TrapOnFailure : public testing::EmptyTestEventListener {
  void OnTestPartResult(const testing::TestPartResult& result) override {
    if (!result.failed()) return;
    std::fprintf(stderr, "%s:%d: %s\n", result.file_name() ? result.file_name() : "?", result.line_number(),
                 result.message());
    __builtin_trap();
  }
};

}  // namespace

void trap_on_test_failure() { testing::UnitTest::GetInstance()->listeners().Append(new TrapOnFailure); }

}  // namespace vproxq::fuzz
