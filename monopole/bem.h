// The electrostatic potential of a closed surface (paper 2015, Eqns 11-13): the exterior
// Dirichlet problem for Laplace's equation,
//     laplacian P = 0 outside the surface,  P = 1 on it,  P -> 0 at infinity,
// solved in process with a boundary element method.
//
// Method. P is written as a single-layer potential
//     P(x) = sum_e sigma_e * integral over e of 1 / (4 pi |x - y|) dA_y
// with a charge density sigma that is constant on each element, and P = 1 is collocated at one
// point per element (a dense E x E system, solved by GMRES, LU as fallback). A single layer is
// continuous across the surface and harmonic off it, so once P = 1 holds on the surface it is
// the exterior solution (and P = 1 inside). Integrals over a flat triangle are exact (Wilton et
// al. 1984 closed form) near the evaluation point, Gaussian (6 points, degree 4) at moderate
// distance.
//
// Cost bound. The elements are *patches*: connected groups of input triangles (voxel clustering
// split into connected pieces, slivers merged into a neighbour), so the dense system has at most
// `max_elements` unknowns while the geometry stays the input mesh exactly (no decimation error).
// A far patch acts through its monopole and quadrupole moments (error O((r/d)^3)); near patches
// are integrated triangle by triangle. For a mesh with at most `max_elements` triangles every
// triangle is its own element.
//
// Units: any; P = 1 on the surface whatever the scale. The toolkit passes fractal coordinates.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "quijibo/grid.h"

namespace quijibo::monopole {

struct BemOptions {
  // Upper bound on the number of unknowns (patches) of the dense system. Memory is
  // 8 * max_elements^2 bytes (128 MB for 4000), the LU costs (2/3) max_elements^3 flops.
  int max_elements = 4000;
  // A patch of radius r is "far" from x (moments only) when |x - centre| > far_factor * r.
  double far_factor = 4.0;
  // Within a near patch, a triangle of radius r is integrated exactly when |x - centroid| <
  // exact_factor * r, else with the 6-point Gauss rule.
  double exact_factor = 3.0;
  // Dense solver of the collocation system: GMRES (Jacobi preconditioned, restart 50; O(E^2) per
  // iteration, converges in tens of iterations since the single layer is well conditioned) or
  // partial-pivoting LU (O(E^3)). GMRES falls back to LU when it does not converge.
  enum class Solver { kGmres, kLU };
  Solver solver = Solver::kGmres;
  double solver_tolerance = 1e-12;  // GMRES relative residual
  // Number of input-triangle centroids at which P - 1 is checked after the solve (diagnostic).
  int surface_checks = 1000;

  // Empty string when valid, else what is wrong.
  std::string Validate() const;
};

struct BemSummary {
  int input_triangles = 0;
  int elements = 0;                  // unknowns of the dense system (patches)
  double assembly_seconds = 0.0;
  double solve_seconds = 0.0;
  double relative_residual = 0.0;    // ||A sigma - 1|| / ||1|| of the collocation system
  int solver_iterations = 0;         // GMRES iterations (0 for LU)
  bool used_lu = false;              // LU was used (chosen, or GMRES did not converge)
  double surface_max_deviation = 0.0;  // max |P - 1| at `surface_checks` triangle centroids
  double surface_rms_deviation = 0.0;
  double total_charge = 0.0;  // sum sigma_e area_e; P ~ total_charge / (4 pi |x|) far away
};

// The solved potential. Cheap to copy around (holds the mesh, patches and charges).
class ExteriorPotential {
 public:
  ExteriorPotential() = default;

  // P at one point (any point; inside the surface it is ~1).
  double operator()(const Vec3& x) const;
  // P at many points, in parallel (OpenMP); each value is summed in a fixed order, so the result
  // does not depend on the thread count.
  std::vector<double> Evaluate(const std::vector<Vec3>& points) const;

  int element_count() const { return int(patches_.size()); }
  double total_charge() const;

 private:
  friend ExteriorPotential SolveExteriorPotential(const std::vector<Vec3>&,
                                                  const std::vector<std::array<int, 3>>&,
                                                  const BemOptions&, BemSummary*);
  struct Triangle {
    std::array<Vec3, 3> p;
    Vec3 centroid;
    double area = 0.0;
    double radius = 0.0;  // max distance from the centroid to a corner
  };
  struct Patch {
    int first = 0, count = 0;  // range in triangles_ (sorted by patch)
    Vec3 centroid{};           // area-weighted
    double area = 0.0;
    double radius = 0.0;
    // Second moment of area about the centroid, (xx, yy, zz, xy, xz, yz).
    std::array<double, 6> moment{};
    Vec3 collocation{};        // centroid of the patch's triangle nearest `centroid`
  };
  // integral over patch j of 1 / |x - y| dA_y (no 1/4pi, unit density).
  double PatchIntegral(int j, const Vec3& x) const;
  // triangles_ and patches_ from the mesh's triangles and their patch labels (0 .. count - 1).
  void SetPatches(const std::vector<Triangle>& triangles, const std::vector<int>& label, int count);

  BemOptions options_;
  std::vector<Triangle> triangles_;
  std::vector<Patch> patches_;
  std::vector<double> sigma_;  // charge density of each patch
};

// Solves the exterior Dirichlet problem P = 1 on the closed triangle mesh (vertices, triangles).
// Inputs:
//   vertices, triangles  a closed, consistently oriented or not (orientation is not used) mesh
//   options              see BemOptions; validated (throws quijibo::Error when invalid)
// Output:
//   the potential, and optionally a summary (elements used, timings, residuals).
// Throws quijibo::Error on an empty mesh, bad indices, or a singular system.
ExteriorPotential SolveExteriorPotential(const std::vector<Vec3>& vertices,
                                         const std::vector<std::array<int, 3>>& triangles,
                                         const BemOptions& options = {},
                                         BemSummary* summary = nullptr);

// integral over the flat triangle (a, b, c) of 1 / |x - y| dA_y, in closed form (Wilton, Rao,
// Glisson, Schaubert, Al-Bundak, Butler 1984). Exact for x anywhere, including on the triangle.
double TriangleInverseDistanceIntegral(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace quijibo::monopole
