// quijibo-mpi when the build found no MPI: says that the feature is off (docs/mpi.md).
#include <cstdio>

int main(int, char**) {
  std::fprintf(stderr,
               "quijibo-mpi: error: MPI support is off in this build (CMake found no MPI, or QUIJIBO_WITH_MPI=OFF).\n"
               "Install Open MPI (Debian: mpi-default-dev mpi-default-bin, or ./scripts/install-deps.sh) and\n"
               "reconfigure (with -DQUIJIBO_WITH_MPI=ON, the default); meanwhile `quijibo mesh` meshes on one machine "
               "(docs/mpi.md).\n");
  return 2;
}
