// Optimizer logs (log.jsonl, optim/optimizer.h) as a convergence plot reads them.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace quijibo::pipeline {

// What a plot needs from one optimizer log.
struct ConvergenceLog {
  struct Point {
    long long step;
    double energy;  // psi in [-1, 1]
  };
  struct PassMark {
    long long step;
    std::string label;  // "25 V": level and pass, as far as the log names them
  };
  std::string path;
  nlohmann::json run;  // the "run" header line, or null
  // Relative energies of "iteration" lines, one segment per pass (a pass starts at a
  // "pass_start" line or where level/pass of the iteration lines change).
  std::vector<std::vector<Point>> relative;
  // Absolute energies: "absolute" lines, plus the "absolute_end" of "pass_end" lines and the
  // "absolute_energy" of the "run" line (the start) at steps no "absolute" line covers; sorted by
  // step. A run whose passes made no iteration has only these.
  std::vector<Point> absolute;
  std::vector<PassMark> passes;
  bool truncated = false;  // the unparsable last line was skipped
};

// Whether a log has anything to draw.
bool HasEnergies(const ConvergenceLog& log);

// Reads a log.jsonl. Unknown line types and keys are ignored; an energy of null (NaN) is
// skipped. An unparsable last line (a killed run) is skipped with a warning on stderr; any other
// bad line throws quijibo::Error naming "<path>:<line>".
ConvergenceLog ReadConvergenceLog(const std::string& path);

}  // namespace quijibo::pipeline
