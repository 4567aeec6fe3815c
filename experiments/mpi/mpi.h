// quijibo-mpi (docs/mpi.md): `quijibo mesh` over MPI ranks (mesh.cpp) and parameter sweeps of
// `quijibo` commands (sweep.cpp), both over one work queue (work_queue.h).
#pragma once

#include <CLI/CLI.hpp>

#include "experiments/pipeline/mesh.h"

namespace quijibo::mpi {

// A pipeline::Mesher over the ranks: the single-process mesh, bit for bit; false on workers.
bool MpiMesher(const mesh::BatchField& field, const mesh::MeshingOptions& options, mesh::MeshingSummary* summary,
               mesh::FieldBand* band, mesh::TriangleMesh* mesh, mesh::JuliaFieldStats* stats);

// A pipeline::StreamMesher over the ranks: rank 0 streams the pieces to the PLY as they arrive (the
// single-process file, byte for byte); nothing on workers.
std::optional<mesh::MeshStreamReport> MpiStreamMesher(const mesh::BatchField& field,
                                                      const mesh::MeshingOptions& options,
                                                      const mesh::MeshStreamOptions& stream,
                                                      mesh::MeshingSummary* summary, mesh::JuliaFieldStats* stats);

// `quijibo-mpi sweep SWEEP.json`.
void AddSweep(CLI::App& app);

}  // namespace quijibo::mpi
