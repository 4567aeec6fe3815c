// The mesher's command-line options, one definition shared by `quijibo mesh`, `quijibo modulus` and
// `quijibo portal` (docs/meshing.md); its summary is pipeline::MesherSummaryJson.
#include "experiments/cli/cli.h"

namespace quijibo::cli {

void AddMesherOptions(CLI::App* c, mesh::MeshingOptions& o) {
  c->add_flag("--dense", [&o](std::int64_t) { o.sparse = false; }, "Evaluate every node (no sparse block search)");
  c->add_option("--tile", o.tile_cells, "Cells per tile side")->capture_default_str();
  c->add_option("--bisection-steps", o.bisection_steps, "Bisection steps per edge")->capture_default_str();
  c->add_flag("--bisection-interpolate", o.bisection_interpolate,
              "After the bisection steps, interpolate linearly in the last bracket (fewer steps, nearly the same "
              "vertices; 0 steps: plain marching cubes)");
  c->add_option("--secant-steps", o.secant_steps,
                "After the bisection steps, false-position steps (the field evaluated where the bracket's line "
                "crosses iso), then the vertex interpolated in the last bracket")
      ->capture_default_str();
  c->add_option("--margin", o.coarse_margin_cells, "Safety margin of the sparse search, cells")->capture_default_str();
  c->add_option("--search-stride", o.search_stride, "Coarsest lattice of the sparse search, cells")
      ->capture_default_str();
  c->add_option("--value-margin", o.search_value_margin,
                "Sparse search: also refine same-side blocks with a corner this close to iso (0: off; default: the "
                "field's, 2 for log|q_n|)");
  c->add_option_function<std::string>(
       "--surface-following", [&o](const std::string& v) { o.follow_surface = v == "on"; },
       "Sparse search: mesh the block across every face of a meshed block that the surface crosses (on: no open "
       "edges away from the box faces; off: the coarse search alone)")
      ->check(CLI::IsMember({"on", "off"}))
      ->default_str("on");
  c->add_option_function<std::string>(
       "--speck-removal", [&o](const std::string& v) { o.remove_specks = v == "on"; },
       "Drop the components that enclose a single lattice node (sub-cell specks that depend on where the lattice "
       "falls); the count is specks_removed")
      ->check(CLI::IsMember({"on", "off"}))
      ->default_str("on");
  c->add_flag("--keep-specks", [&o](std::int64_t) { o.remove_specks = false; }, "Same as --speck-removal off");
}

}  // namespace quijibo::cli
