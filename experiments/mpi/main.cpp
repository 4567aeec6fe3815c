// quijibo-mpi: `quijibo mesh` over MPI ranks, and parameter sweeps of `quijibo` commands (docs/mpi.md).
#include <mpi.h>

#include <cstdio>

#include "experiments/cli/cli.h"
#include "experiments/mpi/mpi.h"
#include "experiments/mpi/work_queue.h"
#include "util/progress.h"

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const int rank = quijibo::mpi::Rank(), size = quijibo::mpi::Size();
  int code = 0;
  {
    CLI::App app{
        "quijibo-mpi: `quijibo mesh` distributed over MPI ranks, and parameter sweeps (docs/mpi.md).\n"
        "Run it under mpirun/srun; every rank gets the same arguments."};
    bool quiet = false;
    quijibo::cli::SetUpApp(app, "quijibo-mpi", quiet, rank != 0);
    quijibo::cli::AddMeshCommand(app, quijibo::mpi::MpiMesher, quijibo::mpi::MpiStreamMesher);
    quijibo::mpi::AddSweep(app);
    try {
      app.parse(argc, argv);
    } catch (const CLI::Success& e) {
      code = rank == 0 ? app.exit(e) : 0;
    } catch (const CLI::ParseError& e) {
      if (rank == 0)
        code = app.exit(e);
      else
        code = e.get_exit_code();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "quijibo-mpi: error (rank %d of %d): %s\n", rank, size, e.what());
      code = 1;
      // Other ranks may be waiting on this one.
      if (size > 1) MPI_Abort(MPI_COMM_WORLD, code);
    }
  }
  MPI_Finalize();
  return code;
}
