// vproxq: batch proximity queries on animated triangle meshes. CLI11 -> Config -> run().
#include "app/allocator.hpp"
#include "app/cli.hpp"

int main(int argc, char** argv) {
  vproxq::keep_freed_memory_for_reuse();
  return vproxq::cli_main(argc, argv);
}
