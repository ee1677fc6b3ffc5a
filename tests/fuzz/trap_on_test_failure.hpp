#pragma once
// For a harness that checks with the test suite's GoogleTest helpers.

namespace vproxq::fuzz {

/// Makes every failed GoogleTest assertion from now on stop the process (a crash libFuzzer
/// records with its input).
void trap_on_test_failure();

}  // namespace vproxq::fuzz
