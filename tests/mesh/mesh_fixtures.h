// Small meshes built in code for the mesh/ tests, and a temporary folder per test.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <string>

#include "mesh/marching_cubes.h"
#include "mesh/triangle_mesh.h"
#include "quijibo/julia.h"
#include "quijibo/rational_map.h"

namespace quijibo::testing {

// A field of a function of one point, for the mesher.
inline mesh::BatchField Lambda(std::function<double(const Vec3&)> f, double iso = 0.0) {
  mesh::BatchField field;
  field.iso = iso;
  field.evaluate = [f](const Vec3* p, std::size_t n, double* v) {
    for (std::size_t i = 0; i < n; ++i) v[i] = f(p[i]);
  };
  return field;
}

// Icosahedron subdivided `levels` times, vertices projected on the sphere (centre, radius),
// faces counter-clockwise seen from outside.
inline mesh::TriangleMesh Icosphere(int levels, const Vec3& centre = {0, 0, 0}, double radius = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  mesh::TriangleMesh m;
  m.vertices = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                 {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                 {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                 {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  auto unit = [](Vec3 p) {
    const double n = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    return Vec3{p[0] / n, p[1] / n, p[2] / n};
  };
  for (auto& v : m.vertices) v = unit(v);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      const Vec3& p = m.vertices[a];
      const Vec3& q = m.vertices[b];
      m.vertices.push_back(unit({p[0] + q[0], p[1] + q[1], p[2] + q[2]}));
      return mid[key] = int(m.vertices.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const auto& f : m.triangles) {
      const int a = midpoint(f[0], f[1]), b = midpoint(f[1], f[2]), c = midpoint(f[2], f[0]);
      next.push_back({f[0], a, c});
      next.push_back({f[1], b, a});
      next.push_back({f[2], c, b});
      next.push_back({a, b, c});
    }
    m.triangles = std::move(next);
  }
  for (auto& v : m.vertices)
    for (int a = 0; a < 3; ++a) v[a] = centre[a] + radius * v[a];
  return m;
}

// A fresh empty folder under the system temp dir, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = std::filesystem::temp_directory_path() /
            ("quijibo-mesh-" + std::string(info->test_suite_name()) + "-" + info->name() + "-" +
             std::to_string(std::random_device{}()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(file(name), std::ios::binary) << bytes;
    return file(name);
  }
  std::size_t count() const {
    return std::size_t(std::distance(std::filesystem::directory_iterator(path_),
                                     std::filesystem::directory_iterator()));
  }

 private:
  std::filesystem::path path_;
};

// The mesh as a multiset of triangles of positions, each rotated so its smallest vertex comes
// first: equal for two meshes that differ only in vertex and face order.
inline std::multiset<std::array<Vec3, 3>> Canonical(const mesh::TriangleMesh& m) {
  std::multiset<std::array<Vec3, 3>> s;
  for (const auto& t : m.triangles) {
    std::array<Vec3, 3> p{m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]]};
    const int first = int(std::min_element(p.begin(), p.end()) - p.begin());
    std::rotate(p.begin(), p.begin() + first, p.end());
    s.insert(p);
  }
  return s;
}

// A small random map (12 top, 9 bottom roots) whose set at n = 1 contains the origin: ln C puts
// L(0) at -1; with or without roots at the origin.
inline RationalMap SmallSetMap(bool zero_roots = false) {
  RationalMap m = RandomMap({.top = 12, .bottom = 9, .root_radius = 1.2, .exponent_min = 0.3, .exponent_max = 1.2,
                             .leading_zero_roots = zero_roots, .seed = 4});
  m.ln_C = 0;
  JuliaOptions j;
  j.iterations = 1;
  m.ln_C = -1.0 - JuliaMap<double>(m, j).At({0, 0, 0}).log_modulus;
  return m;
}

}  // namespace quijibo::testing
