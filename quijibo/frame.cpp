#include "quijibo/frame.h"

#include <cmath>

#include "quijibo/error.h"

namespace quijibo {

std::string FractalFrame::validate() const {
  if (!(fractal_radius > 0.0) || !std::isfinite(fractal_radius))
    return "fractal_radius must be a positive finite number";
  if (!(padding >= 0.0 && padding < 0.5)) return "padding must be in [0, 0.5)";
  if (!(scale > 0.0) || !std::isfinite(scale)) return "scale must be a positive finite number";
  for (double t : translation)
    if (!std::isfinite(t)) return "translation must be finite";
  for (double o : origin)
    if (!(o >= 0.0 && o <= 1.0)) return "origin must lie in the unit cube [0, 1]^3";
  return {};
}

TargetBox ParseTargetBox(const std::string& name) {
  if (name == "unit") return TargetBox::kUnitCube;
  if (name == "reference") return TargetBox::kReference;
  throw Error("unknown target box \"" + name + "\" (expected unit or reference)");
}

std::string TargetBoxName(TargetBox box) { return box == TargetBox::kUnitCube ? "unit" : "reference"; }

GridFrame TargetGridFrame(int n, const FractalFrame& frame, TargetBox box) {
  const double side = box == TargetBox::kUnitCube
                          ? frame.fractal_radius
                          : frame.fractal_radius * (1.0 - 2.0 * frame.padding) * (n + 2.0) / n;
  return GridFrame::Cube(n, frame.box_center(), side);
}

}  // namespace quijibo
