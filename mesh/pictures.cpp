#include "mesh/pictures.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "quijibo/grid.h"
#include "util/error.h"

namespace quijibo::mesh {

std::string SliceView::Validate() const {
  if (axis < 0 || axis > 2) return "slice axis must be x, y or z";
  if (size < 8 || size > 16384) return "picture size must be in [8, 16384]";
  for (int a = 0; a < 3; ++a)
    if (!(max_corner[a] > min_corner[a]) || !std::isfinite(min_corner[a]) || !std::isfinite(max_corner[a]))
      return "picture box must be finite with max > min";
  if (!std::isfinite(at)) return "slice position must be finite";
  return {};
}

int SliceView::width() const {
  const double w = max_corner[u()] - min_corner[u()], h = max_corner[v()] - min_corner[v()];
  return w >= h ? size : std::max(1, int(std::lround(size * w / h)));
}
int SliceView::height() const {
  const double w = max_corner[u()] - min_corner[u()], h = max_corner[v()] - min_corner[v()];
  return h >= w ? size : std::max(1, int(std::lround(size * h / w)));
}
Vec3 SliceView::point(int px, int py) const {
  Vec3 p{};
  p[axis] = at;
  p[u()] = min_corner[u()] + (max_corner[u()] - min_corner[u()]) * (px + 0.5) / width();
  p[v()] = max_corner[v()] - (max_corner[v()] - min_corner[v()]) * (py + 0.5) / height();
  return p;
}

double SliceAgreement::agreement() const {
  const double n = double(both_inside + both_outside + julia_only + target_only);
  return n > 0 ? double(both_inside + both_outside) / n : 0.0;
}

namespace {

// Evaluates the field on every pixel (rows in parallel).
std::vector<double> EvaluateView(const BatchField& field, const SliceView& view) {
  const int w = view.width(), h = view.height();
  std::vector<double> values(std::size_t(w) * h);
#pragma omp parallel for schedule(dynamic)
  for (int y = 0; y < h; ++y) {
    std::vector<Vec3> row(static_cast<std::size_t>(w));
    for (int x = 0; x < w; ++x) row[std::size_t(x)] = view.point(x, y);
    field.evaluate(row.data(), row.size(), values.data() + std::size_t(y) * w);
  }
  return values;
}

}  // namespace

Image SliceAgainstTarget(const BatchField& field, const ScalarGrid& target, const SliceView& view,
                         SliceAgreement* agreement) {
  if (auto why = view.Validate(); !why.empty()) throw Error("picture: " + why);
  const int w = view.width(), h = view.height();
  const std::vector<double> f = EvaluateView(field, view);
  Image img(w, h);
  SliceAgreement a;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool in_j = f[std::size_t(y) * w + x] < field.iso;
      const bool in_t = target.sample(view.point(x, y)) < 0;
      Rgb c;
      if (in_j && in_t) c = kBothInside, ++a.both_inside;
      else if (!in_j && !in_t) c = kBothOutside, ++a.both_outside;
      else if (in_j) c = kJuliaOnly, ++a.julia_only;
      else c = kTargetOnly, ++a.target_only;
      img.at(x, y) = c;
    }
  if (agreement) *agreement = a;
  return img;
}

Image ModulusVersorSlice(const RationalMap& map, const JuliaOptions& options, const SliceView& view,
                         double modulus_scale, double iso) {
  if (auto why = view.Validate(); !why.empty()) throw Error("picture: " + why);
  if (!(modulus_scale >= 0) || !std::isfinite(modulus_scale)) throw Error("picture: modulus scale must be >= 0");
  const JuliaMap<double> jm(map, options);
  const int w = view.width(), h = view.height();
  std::vector<double> L(std::size_t(w) * h);
  std::vector<JuliaResult<double>> results(L.size());
#pragma omp parallel for schedule(dynamic)
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) results[std::size_t(y) * w + x] = jm.At(view.point(x, y));
  if (modulus_scale == 0) {  // automatic: half the 90th percentile of |log|q_n| - iso|
    std::vector<double> a;
    for (const auto& r : results)
      if (std::isfinite(r.log_modulus)) a.push_back(std::abs(r.log_modulus - iso));
    modulus_scale = 1.0;
    if (!a.empty()) {
      std::nth_element(a.begin(), a.begin() + std::ptrdiff_t(0.9 * double(a.size() - 1)), a.end());
      modulus_scale = std::max(1e-3, 0.5 * a[std::size_t(0.9 * double(a.size() - 1))]);
    }
  }
  Image img(2 * w + 8, h, Rgb{255, 255, 255});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const JuliaResult<double>& r = results[std::size_t(y) * w + x];
      L[std::size_t(y) * w + x] = r.log_modulus;
      const double g = std::isfinite(r.log_modulus) ? 0.5 + 0.5 * std::tanh((r.log_modulus - iso) / modulus_scale)
                                                     : (r.log_modulus < 0 ? 0.0 : 1.0);
      const auto grey = std::uint8_t(std::lround(255 * std::clamp(g, 0.0, 1.0)));
      img.at(x, y) = {grey, grey, grey};
      auto channel = [](double c) { return std::uint8_t(std::lround(127.5 * (1.0 + std::clamp(c, -1.0, 1.0)))); };
      img.at(w + 8 + x, y) = {channel(r.versor.x), channel(r.versor.y), channel(r.versor.z)};
    }
  // The iso line on the modulus panel.
  for (int y = 0; y + 1 < h; ++y)
    for (int x = 0; x + 1 < w; ++x) {
      const bool in = L[std::size_t(y) * w + x] < iso;
      if (in != (L[std::size_t(y) * w + x + 1] < iso) || in != (L[std::size_t(y + 1) * w + x] < iso))
        img.at(x, y) = {220, 30, 30};
    }
  return img;
}

Image InsideSlice(const std::function<double(const Vec3&)>& field, const ScalarGrid& sdf, int size) {
  Image img(size, size);
  const Vec3 lo = sdf.frame.min_corner;
  const Vec3 e = sdf.frame.extent();
  const double side = std::max(e[0], e[1]);
  std::vector<double> f(std::size_t(size) * size), s(f.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const Vec3 p{lo[0] + side * (x + 0.5) / size, lo[1] + side * (size - y - 0.5) / size, 0.0};
      f[std::size_t(y) * size + x] = field(p);
      s[std::size_t(y) * size + x] = ExtendedSample(sdf, p);
    }
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const std::size_t i = std::size_t(y) * size + x;
      img.pixels[i] = f[i] < 0 ? Rgb{0, 0, 0} : Rgb{235, 235, 235};
      const bool edge = (x + 1 < size && (s[i] < 0) != (s[i + 1] < 0)) || (y + 1 < size && (s[i] < 0) != (s[i + size] < 0));
      if (edge) img.pixels[i] = {220, 30, 30};
    }
  return img;
}

}  // namespace quijibo::mesh
