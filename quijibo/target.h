// The target of the energy: a signed distance field phi (negative inside) on a grid, the weight
// field W built from it, and the energy grid of one optimization level.
#pragma once

#include <string>
#include <vector>

#include "quijibo/grid.h"
#include "util/settings.h"

namespace quijibo {

// Analytic targets for tests and demos, sampled on `frame` (fractal frame):
//   "sphere" / "sphere:radius=1.2"          centred at the origin (default radius 1)
//   "torus" / "torus:major=1,minor=0.35"    in the z = 0 plane (defaults 1 and 0.35)
// Throws quijibo::Error on an unknown shape or parameter.
ScalarGrid AnalyticTarget(const std::string& spec, const GridFrame& frame);

// Which weight field W the energy uses (paper Eqn 6 or the reference code, quijibo-code §4.4).
enum class WeightField {
  // Reference default: inverse 6-connected grid-layer distance to the sign interface
  // (k = 1 on the cells with a 26-neighbour of the other sign), W = -1/k inside, 1/k outside.
  kLayer,
  // The paper: W = 1/phi, with |phi| clamped to at least half a cell so W stays finite.
  kInverse,
  // The layer weights without the halves' normalization: W = -1/k inside, 1/k outside, scaled
  // only so that sum |W| = 1. A wrongly classified cell then costs the same on either side, as in
  // the IoU; the halves' normalization makes one inside cell worth (sum outside 1/k) /
  // (sum inside 1/k) outside cells (3 for the bunny, 5 to 7 for thin shapes in the unit-cube box), so its optimum
  // grows the set over the outside (docs/benchmarks.md, shape suite).
  kBalanced,
};
// The one default of every face (the optimizer, `quijibo energy`, Python's `energy`), so that an
// energy evaluated on its own is the one the optimizer reports.
inline constexpr WeightField kDefaultWeightField = WeightField::kBalanced;
inline const EnumNames<WeightField> kWeightFields("weight field", {{WeightField::kLayer, "layer"},
                                                                   {WeightField::kInverse, "inverse"},
                                                                   {WeightField::kBalanced, "balanced"}});
inline const std::vector<std::string>& kWeightFieldNames = kWeightFields.names();
inline WeightField ParseWeightField(const std::string& name) { return kWeightFields.Parse(name); }
inline std::string WeightFieldName(WeightField w) { return kWeightFields.Name(w); }

// k = 1 + the 6-connected grid-layer distance of each cell from the sign interface (k = 1 on
// cells with a 26-neighbour of the opposite strict sign): the reference code's layers.
std::vector<int> LayerIndex(const ScalarGrid& sdf);

// W on the grid of `sdf`, normalized as the reference code does: the inside cells (phi < 0)
// sum to -0.5 and the outside cells to +0.5, so sum |W| = 1 (kBalanced: only sum |W| = 1). Throws if the field has no inside
// or no outside cell.
std::vector<double> ComputeWeights(const ScalarGrid& sdf, WeightField field);

// How a coarse level gets its weights (issue: levels).
enum class LevelWeights {
  kSampleFinest,  // trilinear samples of the finest W (the reference code)
  kRecompute,     // sample phi on the level grid and rebuild W there
};
inline const EnumNames<LevelWeights> kLevelWeights("level weights", {{LevelWeights::kSampleFinest, "sample"},
                                                                    {LevelWeights::kRecompute, "recompute"}});
inline const std::vector<std::string>& kLevelWeightNames = kLevelWeights.names();
inline LevelWeights ParseLevelWeights(const std::string& name) { return kLevelWeights.Parse(name); }
inline std::string LevelWeightsName(LevelWeights w) { return kLevelWeights.Name(w); }

// The sample points and weights of one level. Sample c is the quaternion
// [x_c, y_c, z_c, slice] with (x_c, y_c, z_c) = frame.cell_center(c).
struct EnergyGrid {
  GridFrame frame;
  double slice = 0.0;
  std::vector<double> weight;
  double eta = 0.0;  // sum |W| on this grid (paper Eqn 7)
};

// The level of resolution n (cells along the longest axis; n <= 0: the SDF grid itself) over
// the same box as `sdf`.
EnergyGrid MakeEnergyGrid(const ScalarGrid& sdf, WeightField field, int n = 0,
                          LevelWeights level_weights = LevelWeights::kSampleFinest,
                          double slice = 0.0);
// Same, from a precomputed finest weight field (avoids recomputing W at every level).
EnergyGrid MakeEnergyGrid(const ScalarGrid& sdf, const std::vector<double>& finest_weight,
                          WeightField field, int n, LevelWeights level_weights, double slice);

// The interior cell corners of `level` as a grid of their own (each corner the centre of eight of
// the level's cells: dims - 1 cells per axis, shifted by half a cell), its weights those of `field`
// computed from `sdf` sampled trilinearly at the corners (sampling the nodes' weights instead
// would give the corners beside a thin wall, between an inside and an outside node, weights near
// 0: no say where it matters), eta their sum of |W|. The energy on both grids sees what a fit does
// between the level's nodes as well as on them (optim's `between_nodes`). Throws quijibo::Error
// when the level has fewer than two cells along an axis.
EnergyGrid CornerGrid(const ScalarGrid& sdf, WeightField field, const EnergyGrid& level);

// How well a level represents the target, in [0, 1]: the IoU between the finest grid's inside
// (W < 0 on `finest`) and the level's inside as the finest cells see it (each finest cell takes
// the sign of W on the `level` cell that contains its centre). 1 on the finest grid itself. A
// level well below 1 fits another shape than the target (a wall or finger thinner than its cells
// vanishes or breaks up there), so its passes move the map away from the target: docs/fidelity.md.
double LevelFidelity(const EnergyGrid& finest, const EnergyGrid& level);

// The resolution a level runs at: the smallest n' in [n, finest] whose LevelFidelity reaches
// `min_fidelity` (the finest resolution when none below it does; n itself when n >= finest or
// min_fidelity <= 0). `fidelity` receives the chosen level's fidelity when not null.
int ResolvedLevelResolution(const ScalarGrid& sdf, const std::vector<double>& finest_weight, WeightField field,
                            int n, LevelWeights level_weights, double min_fidelity, double* fidelity = nullptr);

// How thin a target's walls are against its grid: the 90th percentile of the depth -phi of the
// inside cells, in cells (the shape suite at 97^3: chair 1.2, mug 1.5, genus-3 plate 2.9, trefoil
// 3.3, hand 3.6, double torus 3.7, dragon 3.9, elephant 7.2, bunny 11). 0 when no cell is inside.
double WallDepthCells(const ScalarGrid& sdf);
// A target is thin-walled when WallDepthCells is below this: nearly all of its inside lies within
// four cells of the surface, where a fit passes through the nodes and narrows between them and
// the default root pairs are too sparse to shape the walls (fingers, tubes, slats; measured on the
// suite, docs/fidelity.md §9).
inline constexpr double kThinWallDepthCells = 4.0;

// A switch that follows the target's walls: on, off, or auto (on for a thin-walled target): the
// optimizer's `between_nodes` and the kernel fit's `thin_walls`.
enum class AutoSwitch { kAuto, kOn, kOff };
inline const EnumNames<AutoSwitch> kAutoSwitches("thin-wall switch", {{AutoSwitch::kAuto, "auto"},
                                                                      {AutoSwitch::kOn, "on"},
                                                                      {AutoSwitch::kOff, "off"}});
inline const std::vector<std::string>& kAutoSwitchNames = kAutoSwitches.names();
inline AutoSwitch ParseAutoSwitch(const std::string& name) { return kAutoSwitches.Parse(name); }
inline std::string AutoSwitchName(AutoSwitch s) { return kAutoSwitches.Name(s); }
// Whether `s` is on for the target `sdf` (kAuto: WallDepthCells(sdf) < kThinWallDepthCells).
bool ThinWallsOn(AutoSwitch s, const ScalarGrid& sdf);

}  // namespace quijibo
