// The mesher's command-line options and summary, one definition shared by `quijibo mesh`,
// `quijibo modulus` and `quijibo portal` (docs/meshing.md).
#include "experiments/cli.h"

namespace quijibo::cli {

void AddMesherOptions(CLI::App* c, MeshingOptions& o) {
  c->add_flag("--dense", [&o](std::int64_t) { o.sparse = false; }, "Evaluate every node (no sparse block search)");
  c->add_option("--tile", o.tile_cells, "Cells per tile side")->capture_default_str();
  c->add_option("--bisection-steps", o.bisection_steps, "Bisection steps per edge")->capture_default_str();
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

nlohmann::json MesherSummaryJson(const MeshingSummary& s, const MeshingOptions& o) {
  return {{"sparse", s.search_stride > 0},
          {"vertices", s.vertices},
          {"triangles", s.triangles},
          {"components", s.components},
          {"open_edges", s.open_edges},
          {"open_edges_inside", s.open_edges_inside},
          {"speck_removal", o.remove_specks},
          {"specks_removed", s.specks_removed},
          {"surface_following", o.follow_surface},
          {"blocks_followed", s.blocks_followed},
          {"evaluations",
           {{"nodes", s.nodes_evaluated},
            {"search", s.search_evaluations},
            {"following", s.follow_evaluations},
            {"bisection", s.bisection_evaluations},
            {"non_finite", s.non_finite_values}}},
          {"tiles", {{"meshed", s.tiles_meshed}, {"total", s.tiles_total}}},
          {"blocks", {{"active", s.blocks_active}, {"total", s.blocks_total}}},
          {"seconds", s.seconds}};
}

}  // namespace quijibo::cli
