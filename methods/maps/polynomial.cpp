// Map kind "polynomial": the quaternion polynomial F(q) = q^d + c (2015 Eqn 1 for d = 2; the
// classic quaternion Julia sets, 2015 Fig. 2 and 2024 Fig. 2). A c with zero j and k keeps a start
// in the complex plane there, so its 2D picture is the complex Julia set of z^d + c (the basilica,
// c = -1; the Douady rabbit, c = -0.1226 + 0.7449i).
//   {"kind": "polynomial", "c": [w, i, j, k] (or [re, im]), "degree": d (integer >= 2, default 2)}
// Drawn as the filled Julia set: inside, the orbit stays within the escape radius for n steps.
// The escape radius must be at least max(|c|, 2) for that to be the filled set's test.
#include <cmath>

#include "methods/map_kind.h"

namespace quijibo {

namespace {

class PolynomialMap : public QuaternionMap {
 public:
  PolynomialMap(const Quat& c, int degree) : c_(c), degree_(degree) {}
  Quat Apply(const Quat& q) const override {
    Quat p = q;
    for (int i = 1; i < degree_; ++i) p = p * q;
    return p + c_;
  }

 private:
  Quat c_;
  int degree_;
};

}  // namespace

MapKind MapKind_polynomial() {
  MapKind k;
  k.name = "polynomial";
  k.help = "q^d + c: \"c\" [w, i, j, k] or [re, im], \"degree\" d (integer >= 2, default 2); the filled Julia set";
  k.keys = {"c", "degree"};
  k.iteration.iterations = 20;
  k.iteration.escape_radius = 4.0;
  k.iteration.bounded = true;
  k.half_extent = 1.5;
  k.read = [](const JsonReader& r, const std::string& p, const std::string&) {
    const std::size_t n = r.array_size(p + "/c");
    if (n != 2 && n != 4) r.fail(p + "/c", "expected 2 (complex) or 4 (quaternion) numbers");
    double c[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < n; ++i) c[i] = r.number(p + "/c/" + std::to_string(i));
    const double d = r.number_or(p + "/degree", 2.0);
    if (!(d >= 2 && d <= 64 && d == std::floor(d))) r.fail(p + "/degree", "expected an integer in [2, 64]");
    KindMap m;
    m.map = std::make_shared<PolynomialMap>(Quat{c[0], c[1], c[2], c[3]}, int(d));
    return m;
  };
  return k;
}

}  // namespace quijibo
