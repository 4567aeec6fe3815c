// The quality of a run's result, stated (report.md's "Quality" section, run.json's "quality"): the
// fidelity figures of the chosen map (mesh/fidelity.h: one-step and n-step IoU and leak), the
// mesh's components and open edges, the start check (inverted, saturated), the shape modulus'
// origin, and a warning wherever a figure says the result is not what it may look like. The
// thresholds and why: docs/experiments.md, "Quality of the result".
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "experiments/pipeline/experiment.h"
#include "mesh/fidelity.h"
#include "quijibo/grid.h"
#include "quijibo/rational_map.h"

namespace quijibo::pipeline {

struct QualityThresholds {
  double min_iou = 0.5;        // one-step or n-step IoU below: the set does not follow the shape
  double coarse_iou = 0.8;     // one-step IoU below (and at least min_iou): it follows the shape coarsely
  double max_leak = 0.05;      // one-step or n-step leak above: set outside the shape box
  double max_fill = 0.5;       // fraction of the lattice in the n-step set above: it fills the box
  double max_saturated = 0.5;  // fraction of the start's cells with tanh flat above: no gradient
  double max_iou_loss = 0.002;  // one-step IoU on the target grid lost by the optimization above
  double max_node_gap = 0.05;   // one-step IoU between the target grid's nodes below the nodes' by more
};

// `x` with `digits` decimals, as report.md writes its figures.
std::string Fixed(double x, int digits);

struct QualityOptions {
  // Lattice nodes per axis. 32: on the bunny's log-kernel map (401 roots, n = 4) the IoU and leak
  // are within 0.01 and 3 % of `quijibo fidelity`'s 72^3 figures (0.722 / 0.110 / 4.37 against
  // 0.712 / 0.113 / 4.24) for an eleventh of the work: seconds, not most of a minute.
  int lattice = 32;
  // `chosen` as the mesh stage iterates it (its `detail` and `iteration_frame` applied: the run's
  // iterated map, MeshStageOptions::Iterated); needed when the n-step set is measured.
  std::shared_ptr<const RationalMap> iterated;
};

// The measuring of `quijibo run`'s fidelity stage (fidelity/fidelity.json): the fidelity figures of
// `chosen` on `target` with the mesh's n and iso, and the start check of `initial` with the
// energy's `alpha` (`start`, when not null, is that check as the initial stage made it:
// monopoles.json's "start").
nlohmann::json MeasureQuality(const RationalMap& initial, const RationalMap& chosen, const ScalarGrid& target,
                              const JuliaOptions& julia, double iso, double alpha, const nlohmann::json& start,
                              const QualityOptions& options = {});

// The figures and warnings of the run in `results`, from its stages' files: {"figures": {...},
// "warnings": [...]}, or null when no stage measured anything.
nlohmann::json RunQuality(const Experiment& experiment, const std::string& results,
                          const QualityThresholds& thresholds = {});

// report.md's "Quality" section of RunQuality's answer ("" for null).
std::string QualitySection(const nlohmann::json& quality);

}  // namespace quijibo::pipeline
