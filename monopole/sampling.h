// Blue-noise (Poisson-disk-like) points on a triangle mesh: the monopole candidates of the
// 2015 paper's Alg. 1 (the reference code used vcglib's Poisson sampling with ~1e6 points).
//
// Method: weighted sample elimination (Yuksel 2015). Draw oversampling * count uniform random
// points on the surface (area-weighted), then repeatedly remove the point most crowded by its
// neighbours within 2 r_max (r_max = sqrt(area / (2 sqrt(3) count)), the densest packing radius)
// until exactly `count` remain. Distances are Euclidean in 3D. Deterministic for a seed: the
// random numbers come from std::mt19937_64 turned into doubles by hand (no std distributions,
// whose algorithms differ between standard libraries), and ties are broken by index.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo::monopole {

struct SamplingOptions {
  // Points returned (exactly). The fit examines 100 per step: fitting P takes ~30 steps on the
  // tooth and bunny, fitting 1 - P (the reference code's target) 500-600.
  int count = 100000;
  double oversampling = 5.0;  // uniform points drawn per returned point (Yuksel uses 5)
  std::uint64_t seed = 5489;  // std::mt19937_64 seed

  // Empty string when valid, else what is wrong.
  std::string Validate() const;
};

// Blue-noise points on the mesh surface.
// Inputs:
//   vertices, triangles  the mesh (any orientation; degenerate triangles get no points)
//   options              see SamplingOptions; validated (throws quijibo::Error when invalid)
// Output: exactly options.count points on the surface, in a random (seeded) order.
// Throws quijibo::Error on an empty mesh, bad indices or a mesh without area.
std::vector<Vec3> PoissonDiskSample(const std::vector<Vec3>& vertices,
                                    const std::vector<std::array<int, 3>>& triangles,
                                    const SamplingOptions& options = {});

// Uniform double in [0, 1) from the top 53 bits of one draw (portable across standard libraries).
double UniformDouble(std::uint64_t bits);

}  // namespace quijibo::monopole
