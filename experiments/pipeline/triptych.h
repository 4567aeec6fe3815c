// The 2015 paper's Fig. 1 for the user's mesh, at the end of every QUIJIBO run: (a) the target,
// (b) the Julia set as the mesh stage makes it, (c) an intricate surface of the same map (fractal
// detail and the root translation by potential, docs/meshing.md "The triptych"), rendered alike
// side by side, with one line of figures under each (report.md opens with it).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "experiments/pipeline/mesh.h"
#include "mesh/render.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/grid.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

// The intricate surface's settings before the experiment's "intricate" section is read: the mesh
// stage's (n, escape, iso, precision, kernel, which optimizer, and whether it is on: an experiment
// without meshes gets none) with detail 4, the translation by potential -2 along z in the map's
// frame, 128^3 cells, a .vdb. Why these: docs/meshing.md
// "The triptych" (measured on the shape suite).
MeshStageOptions IntricateDefaults(const MeshStageOptions& mesh);

// The fidelity figures of the set `o` meshes (its detail, frame and translation) of `map` on the
// lattice of `lattice`^3 nodes over the target grid `target` (mesh/fidelity.h: n-step IoU, closed
// IoU, leak), as fidelity.json holds them for the mesh stage's set. The run measures the intricate
// surface on the Quality section's lattice (QualityOptions::lattice, 32), as the set is measured
// there, so the two lines of figures compare.
// `setup` is `map` as the intricate surface iterates it (o.Iterated(map)).
nlohmann::json SetFidelity(const RationalMap& map, const JuliaSetup& setup, const ScalarGrid& target,
                           const MeshStageOptions& o, int lattice);

// The three renders of the triptych into `dir`: target.png, set.png, intricate.png (each
// `size` pixels square, one three-quarter view, framed alike on the target mesh) and
// triptych.png (the three side by side). A path may be empty (that panel is left out). Returns
// {"seconds": ..., "panels": [...], "triangles": [...]}.
nlohmann::json RenderTriptych(const std::string& target_mesh, const std::string& set_mesh,
                              const std::string& intricate_mesh, const mesh::RenderOptions& render, int size,
                              const std::string& dir);

// report.md's opening triptych (Markdown) from the results folder's files; "" when the run drew
// none.
std::string TriptychSection(const std::string& results);

}  // namespace quijibo::pipeline
