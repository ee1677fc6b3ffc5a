#pragma once
// Command line: `vproxq SCENE [options]` and `vproxq diff A.json B.json [options]`.

namespace vproxq {

/// Parses the arguments, runs, and maps errors to the documented exit codes (README).
int cli_main(int argc, char** argv);

}  // namespace vproxq
