// Test meshes for the monopole tests (header only, not a test file itself).
#pragma once

#include <array>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo::testing {

struct TestMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<int, 3>> triangles;
};

// An icosphere: the icosahedron subdivided `levels` times (20 * 4^levels triangles), vertices on
// the sphere of `radius` about `center`, outward (counter-clockwise) orientation.
inline TestMesh MakeIcosphere(int levels, const Vec3& center = {0, 0, 0}, double radius = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {
      {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
      {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
      {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  auto unit = [](Vec3 p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return Vec3{p[0] / n, p[1] / n, p[2] / n};
  };
  for (auto& p : v) p = unit(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(unit({v[a][0] + v[b][0], v[a][1] + v[b][1], v[a][2] + v[b][2]}));
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]),
                c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  TestMesh m;
  for (auto& p : v)
    m.vertices.push_back(
        {center[0] + radius * p[0], center[1] + radius * p[1], center[2] + radius * p[2]});
  m.triangles = f;
  return m;
}

// The exact signed distance of a sphere on an n^3 cube grid of the given side about `center`.
inline ScalarGrid SphereSdf(int n, const Vec3& center, double side, double radius) {
  ScalarGrid g;
  g.frame = GridFrame::Cube(n, center, side);
  g.values.resize(g.frame.cell_count());
  for (std::int64_t c = 0; c < g.frame.cell_count(); ++c) {
    const Vec3 p = g.frame.cell_center(c);
    g.values[c] = std::sqrt((p[0] - center[0]) * (p[0] - center[0]) +
                            (p[1] - center[1]) * (p[1] - center[1]) +
                            (p[2] - center[2]) * (p[2] - center[2])) -
                  radius;
  }
  return g;
}

}  // namespace quijibo::testing
