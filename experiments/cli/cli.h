// Shared pieces of the `quijibo` command line: subcommand registration and target loading.
#pragma once

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <functional>
#include <string>

#include "experiments/pipeline/mesh.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "quijibo/energy.h"
#include "quijibo/grid.h"
#include "quijibo/loglinear_energy.h"
#include "quijibo/real.h"

namespace quijibo::cli {

void AddEnergyCommand(CLI::App& app);
void AddMapCommand(CLI::App& app);
void AddTargetCommand(CLI::App& app);
void AddPlotCommand(CLI::App& app);
void AddOptimizeCommand(CLI::App& app);
// The commands of a concern, and its benchmarks under the `bench` group (`bench`, made by AddCommands).
void AddTargetAndStartCommands(CLI::App& app, CLI::App& bench);  // sdf, monopoles; bench stages
void AddModulusCommands(CLI::App& app, CLI::App& bench);  // modulus, portal, compare; bench modulus
void AddJuliaCommands(CLI::App& app, CLI::App& bench);    // mesh, picture; bench mesh
void AddShapeCommands(CLI::App& app, CLI::App& bench);    // fidelity; bench shapes
void AddBenchPrecisionCommands(CLI::App& bench);          // bench precision (bench_precision.cpp)
void AddBenchBandCommand(CLI::App& bench);                // bench band
void AddRunCommand(CLI::App& app);      // run: JSON experiments end to end (experiments/cli/run.cpp)
void AddFilmCommand(CLI::App& app);     // film: the parameter space as a film (experiments/cli/film.cpp)
void AddReportHtmlCommand(CLI::App& app);  // report-html: a results folder's report.html (run.cpp)
// Every subcommand above, in this order, and `settings` (experiments/cli/commands.cpp).
void AddCommands(CLI::App& app);

// `quijibo mesh` with other meshers, in memory and streamed (quijibo-mpi, docs/mpi.md; pipeline::Mesher,
// pipeline::StreamMesher).
void AddMeshCommand(CLI::App& app, const pipeline::Mesher& mesher, const pipeline::StreamMesher& stream_mesher);

// The mesher's options (--dense, --speck-removal, --surface-following, the sparse search's settings),
// one definition shared by `quijibo mesh`, `modulus` and `portal` (mesher_options.cpp); the
// resolution and box are each command's own.
void AddMesherOptions(CLI::App* command, mesh::MeshingOptions& options);

// A target given on the command line: a .qgrid file, or an analytic shape ("sphere",
// "torus:major=1,minor=0.3") sampled on the default target box (frame.h, TargetGridFrame)
// at `resolution`.
ScalarGrid LoadTarget(const std::string& spec, int resolution);

// Writes text to path atomically, or to stdout when path is empty or "-".
void WriteOutput(const std::string& path, const std::string& text);

// The top of a program's command line: `--version` ("<name> <version>", the project's), a required
// subcommand, and `-q,--quiet` into `quiet` and the progress lines' switch (`silent`: this process
// shows no progress whatever the flag says, as MPI's ranks other than 0).
void SetUpApp(CLI::App& app, const std::string& name, bool& quiet, bool silent = false);

}  // namespace quijibo::cli
