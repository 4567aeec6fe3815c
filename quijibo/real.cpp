#include "quijibo/real.h"

#include "util/error.h"

namespace quijibo {

std::string PrecisionName(Precision p) {
  switch (p) {
    case Precision::kFloat: return "float";
    case Precision::kDouble: return "double";
    case Precision::kLongDouble: return "long-double";
    case Precision::kFloat128: return "float128";
  }
  return "?";
}

Precision ParsePrecision(const std::string& name) {
  if (name == "float") return Precision::kFloat;
  if (name == "double") return Precision::kDouble;
  if (name == "long-double" || name == "long_double" || name == "ld")
    return Precision::kLongDouble;
  if (name == "float128" || name == "quad") return Precision::kFloat128;
  throw Error("unknown precision \"" + name +
              "\": expected one of float, double, long-double, float128");
}

}  // namespace quijibo
