// vproxq: batch proximity queries on animated triangle meshes. CLI11 -> Config -> run().
#include "app/cli.hpp"

int main(int argc, char** argv) { return vproxq::cli_main(argc, argv); }
