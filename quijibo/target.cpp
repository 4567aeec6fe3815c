#include "quijibo/target.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <sstream>

#include "util/error.h"
#include "quijibo/iou.h"

namespace quijibo {

namespace {

// "name:key=value,key=value" -> name and parameters.
std::map<std::string, double> ParseSpec(const std::string& spec, std::string& name) {
  std::map<std::string, double> params;
  const auto colon = spec.find(':');
  name = spec.substr(0, colon);
  if (colon == std::string::npos) return params;
  std::stringstream ss(spec.substr(colon + 1));
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos)
      throw Error("target \"" + spec + "\": expected key=value, found \"" + item + "\"");
    const std::string key = item.substr(0, eq);
    try {
      std::size_t used = 0;
      const double v = std::stod(item.substr(eq + 1), &used);
      if (used != item.size() - eq - 1 || !std::isfinite(v)) throw std::invalid_argument("");
      params[key] = v;
    } catch (const std::exception&) {
      throw Error("target \"" + spec + "\": " + key + " must be a finite number");
    }
  }
  return params;
}

double Take(std::map<std::string, double>& p, const std::string& key, double fallback) {
  auto it = p.find(key);
  if (it == p.end()) return fallback;
  const double v = it->second;
  p.erase(it);
  return v;
}

}  // namespace

ScalarGrid AnalyticTarget(const std::string& spec, const GridFrame& frame) {
  if (auto why = frame.Validate(); !why.empty()) throw Error("target grid: " + why);
  std::string name;
  auto p = ParseSpec(spec, name);
  ScalarGrid g;
  g.frame = frame;
  g.values.resize(std::size_t(frame.cell_count()));
  if (name == "sphere") {
    const double r = Take(p, "radius", 1.0);
    if (!(r > 0)) throw Error("target \"" + spec + "\": radius must be > 0");
    for (std::int64_t c = 0; c < frame.cell_count(); ++c) {
      const Vec3 x = frame.cell_center(c);
      g.values[c] = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - r;
    }
  } else if (name == "torus") {
    const double major = Take(p, "major", 1.0), minor = Take(p, "minor", 0.35);
    if (!(minor > 0 && major > minor))
      throw Error("target \"" + spec + "\": need major > minor > 0");
    for (std::int64_t c = 0; c < frame.cell_count(); ++c) {
      const Vec3 x = frame.cell_center(c);
      const double ring = std::sqrt(x[0] * x[0] + x[1] * x[1]) - major;
      g.values[c] = std::sqrt(ring * ring + x[2] * x[2]) - minor;
    }
  } else {
    throw Error("unknown analytic target \"" + name + "\": expected sphere or torus");
  }
  if (!p.empty())
    throw Error("target \"" + spec + "\": unknown parameter \"" + p.begin()->first + "\"");
  g.quantity = "signed-distance";
  return g;
}

namespace {

// Rescale so the inside sums to -0.5 and the outside to +0.5.
void NormalizeHalves(const ScalarGrid& sdf, std::vector<double>& w) {
  double inside = 0, outside = 0;
  for (std::size_t c = 0; c < w.size(); ++c) (sdf.values[c] < 0 ? inside : outside) += std::abs(w[c]);
  if (inside == 0) throw Error("target has no cell inside the shape: nothing to fit");
  if (outside == 0) throw Error("target has no cell outside the shape: enlarge the grid");
  for (std::size_t c = 0; c < w.size(); ++c) w[c] *= 0.5 / (sdf.values[c] < 0 ? inside : outside);
}

}  // namespace

std::vector<int> LayerIndex(const ScalarGrid& sdf) {
  const GridFrame& f = sdf.frame;
  const int nx = f.dims[0], ny = f.dims[1], nz = f.dims[2];
  const std::size_t n = std::size_t(f.cell_count());
  std::vector<int> layer(n, 0);
  std::deque<std::int64_t> queue;
  auto sign = [&](std::int64_t c) { return sdf.values[c] < 0 ? -1 : (sdf.values[c] > 0 ? 1 : 0); };
  // Shell: a strict sign with a 26-neighbour of the strictly opposite sign.
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        const std::int64_t c = f.index(i, j, k);
        const int s = sign(c);
        if (s == 0) continue;
        bool shell = false;
        for (int dk = -1; dk <= 1 && !shell; ++dk)
          for (int dj = -1; dj <= 1 && !shell; ++dj)
            for (int di = -1; di <= 1 && !shell; ++di) {
              const int a = i + di, b = j + dj, d = k + dk;
              if (a < 0 || b < 0 || d < 0 || a >= nx || b >= ny || d >= nz) continue;
              if (sign(f.index(a, b, d)) == -s) shell = true;
            }
        if (shell) {
          layer[c] = 1;
          queue.push_back(c);
        }
      }
  if (queue.empty()) throw Error("target has no inside/outside interface on its grid");
  // Breadth-first 6-connected layers from the shell.
  while (!queue.empty()) {
    const std::int64_t c = queue.front();
    queue.pop_front();
    const int i = int(c % nx), j = int((c / nx) % ny), k = int(c / (std::int64_t(nx) * ny));
    const int nb[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& d : nb) {
      const int a = i + d[0], b = j + d[1], e = k + d[2];
      if (a < 0 || b < 0 || e < 0 || a >= nx || b >= ny || e >= nz) continue;
      const std::int64_t m = f.index(a, b, e);
      if (layer[m] == 0) {
        layer[m] = layer[c] + 1;
        queue.push_back(m);
      }
    }
  }
  return layer;
}

namespace {

std::vector<double> LayerWeights(const ScalarGrid& sdf) {
  const std::vector<int> layer = LayerIndex(sdf);
  std::vector<double> w(layer.size());
  for (std::size_t c = 0; c < w.size(); ++c) w[c] = (sdf.values[c] < 0 ? -1.0 : 1.0) / layer[c];
  return w;
}

}  // namespace

std::vector<double> ComputeWeights(const ScalarGrid& sdf, WeightField field) {
  std::int64_t inside = 0;
  for (double phi : sdf.values) inside += phi < 0;
  if (inside == 0) throw Error("target has no cell inside the shape: nothing to fit");
  if (inside == std::int64_t(sdf.values.size()))
    throw Error("target has no cell outside the shape: enlarge the grid");
  std::vector<double> w;
  if (field == WeightField::kLayer || field == WeightField::kBalanced) {
    w = LayerWeights(sdf);
  } else {
    const double floor = 0.5 * sdf.frame.spacing;
    w.resize(sdf.values.size());
    for (std::size_t c = 0; c < w.size(); ++c) {
      const double phi = sdf.values[c];
      w[c] = (phi < 0 ? -1.0 : 1.0) / std::max(std::abs(phi), floor);
    }
  }
  if (field == WeightField::kBalanced) {
    double total = 0;
    for (double x : w) total += std::abs(x);
    for (double& x : w) x /= total;
  } else {
    NormalizeHalves(sdf, w);
  }
  return w;
}

EnergyGrid MakeEnergyGrid(const ScalarGrid& sdf, WeightField field, int n,
                          LevelWeights level_weights, double slice) {
  std::vector<double> finest;
  if (n <= 0 || level_weights == LevelWeights::kSampleFinest) finest = ComputeWeights(sdf, field);
  return MakeEnergyGrid(sdf, finest, field, n, level_weights, slice);
}

EnergyGrid MakeEnergyGrid(const ScalarGrid& sdf, const std::vector<double>& finest_weight,
                          WeightField field, int n, LevelWeights level_weights, double slice) {
  if (!std::isfinite(slice)) throw Error("slice must be finite");
  EnergyGrid g;
  g.slice = slice;
  const int finest_n = *std::max_element(sdf.frame.dims.begin(), sdf.frame.dims.end());
  if (n <= 0 || n == finest_n) {
    g.frame = sdf.frame;
    g.weight = finest_weight.empty() ? ComputeWeights(sdf, field) : finest_weight;
  } else {
    if (n < 2) throw Error("level resolution must be >= 2, found " + std::to_string(n));
    g.frame = sdf.frame.resampled(n);
    if (level_weights == LevelWeights::kSampleFinest) {
      ScalarGrid w{sdf.frame, finest_weight, "weight", sdf.coordinates};
      g.weight.resize(std::size_t(g.frame.cell_count()));
      for (std::int64_t c = 0; c < g.frame.cell_count(); ++c) g.weight[c] = w.sample(g.frame.cell_center(c));
    } else {
      ScalarGrid level{g.frame, {}, "signed-distance", sdf.coordinates};
      level.values.resize(std::size_t(g.frame.cell_count()));
      for (std::int64_t c = 0; c < g.frame.cell_count(); ++c)
        level.values[c] = sdf.sample(g.frame.cell_center(c));
      g.weight = ComputeWeights(level, field);
    }
  }
  g.eta = 0;
  for (double w : g.weight) g.eta += std::abs(w);
  if (!(g.eta > 0)) throw Error("the weight field vanishes on this level");
  return g;
}

EnergyGrid CornerGrid(const ScalarGrid& sdf, WeightField field, const EnergyGrid& level) {
  EnergyGrid g;
  g.slice = level.slice;
  g.frame = level.frame;
  for (int a = 0; a < 3; ++a) {
    if (level.frame.dims[a] < 2) throw Error("a level needs two cells along every axis to have interior corners");
    g.frame.dims[a] = level.frame.dims[a] - 1;
    g.frame.min_corner[a] = level.frame.min_corner[a] + 0.5 * level.frame.spacing;
  }
  ScalarGrid corners{g.frame, {}, "signed-distance", sdf.coordinates};
  corners.values.resize(std::size_t(g.frame.cell_count()));
  for (std::int64_t c = 0; c < g.frame.cell_count(); ++c)
    corners.values[std::size_t(c)] = sdf.sample(g.frame.cell_center(c));
  g.weight = ComputeWeights(corners, field);
  g.eta = 0;
  for (double x : g.weight) g.eta += std::abs(x);
  if (!(g.eta > 0)) throw Error("the weight field vanishes on this level's corners");
  return g;
}

double LevelFidelity(const EnergyGrid& finest, const EnergyGrid& level) {
  const GridFrame& f = finest.frame;
  const GridFrame& l = level.frame;
  if (f == l) return 1.0;
  // The level cell holding each finest cell centre, per axis (the frames share their box).
  std::array<std::vector<int>, 3> cell;
  for (int a = 0; a < 3; ++a) {
    cell[a].resize(std::size_t(f.dims[a]));
    for (int i = 0; i < f.dims[a]; ++i) {
      const double x = f.min_corner[a] + f.spacing * (i + 0.5);
      cell[a][std::size_t(i)] = std::clamp(int(std::floor((x - l.min_corner[a]) / l.spacing)), 0, l.dims[a] - 1);
    }
  }
  long long both = 0, either = 0;
  for (int k = 0; k < f.dims[2]; ++k)
    for (int j = 0; j < f.dims[1]; ++j)
      for (int i = 0; i < f.dims[0]; ++i) {
        const bool in_f = finest.weight[std::size_t(f.index(i, j, k))] < 0;
        const bool in_l = level.weight[std::size_t(l.index(cell[0][std::size_t(i)], cell[1][std::size_t(j)],
                                                           cell[2][std::size_t(k)]))] < 0;
        both += in_f && in_l;
        either += in_f || in_l;
      }
  return IntersectionOverUnion(both, either);
}

int ResolvedLevelResolution(const ScalarGrid& sdf, const std::vector<double>& finest_weight, WeightField field,
                            int n, LevelWeights level_weights, double min_fidelity, double* fidelity) {
  const int finest_n = *std::max_element(sdf.frame.dims.begin(), sdf.frame.dims.end());
  double fid = 1.0;
  int m = n;
  if (n < finest_n) {
    const EnergyGrid finest = MakeEnergyGrid(sdf, finest_weight, field, 0, level_weights, 0.0);
    for (m = n; m < finest_n; ++m) {
      fid = LevelFidelity(finest, MakeEnergyGrid(sdf, finest_weight, field, m, level_weights, 0.0));
      if (min_fidelity <= 0 || fid >= min_fidelity) break;
    }
    if (m == finest_n) fid = 1.0;
  }
  if (fidelity) *fidelity = fid;
  return m;
}

double WallDepthCells(const ScalarGrid& sdf) {
  std::vector<double> depth;
  for (double phi : sdf.values)
    if (phi < 0) depth.push_back(-phi / sdf.frame.spacing);
  if (depth.empty()) return 0.0;
  const auto k = std::ptrdiff_t(0.9 * double(depth.size() - 1));
  std::nth_element(depth.begin(), depth.begin() + k, depth.end());
  return depth[std::size_t(k)];
}

bool ThinWallsOn(AutoSwitch s, const ScalarGrid& sdf) {
  if (s != AutoSwitch::kAuto) return s == AutoSwitch::kOn;
  return WallDepthCells(sdf) < kThinWallDepthCells;
}

}  // namespace quijibo
