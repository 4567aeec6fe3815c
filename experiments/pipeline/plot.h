// The plot stage: convergence plots of optimizer logs (log.jsonl), like Fig. 11 of the QUIJIBO
// paper (Kim 2015): normalized energy (psi + 1) / 2 on a log axis against the optimization step,
// the relative energy (current level's grid and weights) as a line, the absolute energy (finest
// grid, original weights) as dashed line with points, and pass starts as dashed vertical lines
// labelled "<level> <pass>" ("25 V", "50 F", ...). Drawn by gnuplot into PREFIX.png and PREFIX.svg.
#pragma once

#include <string>
#include <vector>

#include "experiments/pipeline/convergence_log.h"
#include "experiments/pipeline/settings.h"

namespace quijibo::pipeline {

struct PlotOptions {
  std::vector<std::string> logs;    // log.jsonl files, one curve pair each
  std::vector<std::string> labels;  // legend names in order (default: the run's "label", else the
                                    // file's stem, or its folder's name for log.jsonl)
  std::string out;                  // the prefix: PREFIX.png and PREFIX.svg
  std::string title;                // default: QUIJIBO convergence[: label (backend, ...)]
  int width = 1200, height = 700;   // pixels
  static const Schema<PlotOptions>& Settings();
};

// Draws the plot. Throws quijibo::Error (gnuplot missing or failing, a log without energies, a
// missing output folder) and then leaves no output file.
void Plot(const PlotOptions& options);

}  // namespace quijibo::pipeline
