#include "quijibo/grid.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "util/error.h"
#include "util/io.h"

namespace quijibo {

static_assert(std::endian::native == std::endian::little,
              "the .qgrid reader and writer assume a little-endian machine");

namespace {
constexpr char kMagic[8] = {'Q', 'J', 'B', 'G', 'R', 'I', 'D', '1'};
constexpr std::int64_t kMaxCells = std::int64_t(1) << 34;  // 16 Gi cells: a sanity bound
}  // namespace

GridFrame GridFrame::Cube(int n, const Vec3& center, double side) {
  GridFrame f;
  f.dims = {n, n, n};
  f.spacing = side / n;
  for (int a = 0; a < 3; ++a) f.min_corner[a] = center[a] - 0.5 * side;
  return f;
}

Vec3 GridFrame::cell_center(std::int64_t index) const {
  const int i = int(index % dims[0]);
  const std::int64_t rest = index / dims[0];
  const int j = int(rest % dims[1]);
  const int k = int(rest / dims[1]);
  return cell_center(i, j, k);
}

Vec3 GridFrame::center() const {
  return {min_corner[0] + 0.5 * spacing * dims[0], min_corner[1] + 0.5 * spacing * dims[1],
          min_corner[2] + 0.5 * spacing * dims[2]};
}

GridFrame GridFrame::resampled(int n) const {
  const Vec3 c = center();
  const Vec3 e = extent();
  const double longest = std::max({e[0], e[1], e[2]});
  GridFrame f;
  f.spacing = longest / n;
  for (int a = 0; a < 3; ++a) {
    f.dims[a] = std::max(1, int(std::lround(e[a] / f.spacing)));
    f.min_corner[a] = c[a] - 0.5 * f.spacing * f.dims[a];
  }
  return f;
}

std::string GridFrame::Validate() const {
  for (int a = 0; a < 3; ++a) {
    if (dims[a] < 1) return "grid dimensions must be positive, found " + std::to_string(dims[a]);
    if (!std::isfinite(min_corner[a])) return "grid corner must be finite";
  }
  if (!(spacing > 0.0) || !std::isfinite(spacing))
    return "grid spacing must be a positive finite number";
  if (cell_count() > kMaxCells) return "grid has more than 2^34 cells";
  return {};
}

double ScalarGrid::sample(const Vec3& p) const {
  // Continuous index of p in cell-centre coordinates.
  int i0[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    double u = (p[a] - frame.min_corner[a]) / frame.spacing - 0.5;
    u = std::clamp(u, 0.0, double(frame.dims[a] - 1));
    i0[a] = std::min(int(std::floor(u)), std::max(frame.dims[a] - 2, 0));
    t[a] = frame.dims[a] > 1 ? u - i0[a] : 0.0;
  }
  auto v = [&](int di, int dj, int dk) {
    const int i = std::min(i0[0] + di, frame.dims[0] - 1);
    const int j = std::min(i0[1] + dj, frame.dims[1] - 1);
    const int k = std::min(i0[2] + dk, frame.dims[2] - 1);
    return values[frame.index(i, j, k)];
  };
  const double c00 = v(0, 0, 0) * (1 - t[0]) + v(1, 0, 0) * t[0];
  const double c10 = v(0, 1, 0) * (1 - t[0]) + v(1, 1, 0) * t[0];
  const double c01 = v(0, 0, 1) * (1 - t[0]) + v(1, 0, 1) * t[0];
  const double c11 = v(0, 1, 1) * (1 - t[0]) + v(1, 1, 1) * t[0];
  const double c0 = c00 * (1 - t[1]) + c10 * t[1];
  const double c1 = c01 * (1 - t[1]) + c11 * t[1];
  return c0 * (1 - t[2]) + c1 * t[2];
}

void WriteGrid(const std::string& path, const ScalarGrid& grid) {
  if (const std::string why = grid.frame.Validate(); !why.empty())
    throw Error(path + ": cannot write grid: " + why);
  if (std::int64_t(grid.values.size()) != grid.frame.cell_count())
    throw Error(path + ": cannot write grid: value count does not match its dimensions");
  nlohmann::json h;
  h["dims"] = grid.frame.dims;
  h["min_corner"] = grid.frame.min_corner;
  h["spacing"] = grid.frame.spacing;
  h["sample"] = "cell-center";
  h["order"] = "x-fastest";
  h["value_type"] = "float64-le";
  h["quantity"] = grid.quantity;
  h["coordinates"] = grid.coordinates;
  const std::string header = h.dump();
  std::string bytes(kMagic, 8);
  const std::uint32_t n = std::uint32_t(header.size());
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  bytes += header;
  bytes.append(reinterpret_cast<const char*>(grid.values.data()),
               grid.values.size() * sizeof(double));
  WriteFileAtomically(path, bytes);
}

ScalarGrid ReadGrid(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open grid file: " + std::strerror(errno));
  char magic[8];
  if (!in.read(magic, 8) || std::memcmp(magic, kMagic, 8) != 0)
    throw Error(path + ": not a .qgrid file (expected the magic bytes QJBGRID1 at offset 0)");
  std::uint32_t n = 0;
  if (!in.read(reinterpret_cast<char*>(&n), 4) || n == 0 || n > (1u << 20))
    throw Error(path + ": corrupt .qgrid header length at offset 8");
  std::string header(n, '\0');
  if (!in.read(header.data(), n)) throw Error(path + ": truncated .qgrid header");
  ScalarGrid g;
  try {
    const nlohmann::json h = nlohmann::json::parse(header);
    g.frame.dims = h.at("dims").get<std::array<int, 3>>();
    g.frame.min_corner = h.at("min_corner").get<Vec3>();
    g.frame.spacing = h.at("spacing").get<double>();
    if (h.value("sample", "cell-center") != "cell-center")
      throw Error(path + ": header /sample: expected \"cell-center\"");
    if (h.value("value_type", "float64-le") != "float64-le")
      throw Error(path + ": header /value_type: expected \"float64-le\"");
    g.quantity = h.value("quantity", "signed-distance");
    g.coordinates = h.value("coordinates", "fractal");
  } catch (const nlohmann::json::exception& e) {
    throw Error(path + ": bad .qgrid header: " + e.what());
  }
  if (const std::string why = g.frame.Validate(); !why.empty()) throw Error(path + ": " + why);
  g.values.resize(std::size_t(g.frame.cell_count()));
  if (!in.read(reinterpret_cast<char*>(g.values.data()),
               std::streamsize(g.values.size() * sizeof(double))))
    throw Error(path + ": truncated .qgrid data: expected " +
                std::to_string(g.frame.cell_count()) + " float64 values");
  for (std::size_t c = 0; c < g.values.size(); ++c)
    if (!std::isfinite(g.values[c]))
      throw Error(path + ": value " + std::to_string(c) + " is not finite");
  return g;
}

double ExtendedSample(const ScalarGrid& grid, const Vec3& p) {
  // Clamp to the box of cell centres (where the trilinear sample is defined), add the distance.
  Vec3 c;
  double d2 = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double lo = grid.frame.min_corner[a] + 0.5 * grid.frame.spacing;
    const double hi = lo + grid.frame.spacing * (grid.frame.dims[a] - 1);
    c[a] = std::clamp(p[a], lo, hi);
    const double e = p[a] - c[a];
    d2 += e * e;
  }
  const double v = grid.sample(c);
  return d2 > 0.0 ? v + std::sqrt(d2) : v;
}

}  // namespace quijibo
