// The iterated map of a QUIJIBO run, made once: a map with the settings that say how it is iterated
// (frame, detail, root translation, box, rotation, n, escape), for the mesh stage, the fidelity
// measures, the pictures and every face that meshes (the command line, MPI, Python).
//
// The n-step set is that of IterationMap(map, frame, detail) (rational_map.h), with the
// root translation given (`translate`) or chosen by the potential it leaves at -t
// (`translate_potential`, TranslationForPotential), sampled over `box` (default: the map's
// normalized cube in the iteration frame) turned by `rotation` about the box's centre.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quijibo/julia.h"
#include "quijibo/quaternion_map.h"
#include "quijibo/rational_map.h"

namespace quijibo {

struct JuliaSetupOptions {
  JuliaOptions julia;             // n, escape and capture radius, slice, root scale; its translation when none below
  IterationFrame frame = IterationFrame::kMap;  // kReference: where the paper's translations are given
  double detail = kSmoothDetail;  // WithDetail's band width, percent of the shape's size; 0: as optimized
  std::optional<std::vector<double>> translate;  // x, y, z[, k]; with translate_potential: its direction
  std::optional<double> translate_potential;     // L = log|R| wanted at -t, in [-1000, 0)
  std::vector<double> box;       // xmin, ymin, zmin, xmax, ymax, zmax in the iteration frame; empty: the cube
  std::vector<double> rotation;  // ax, ay, az, degrees about the box's centre; empty: none
  std::string Validate() const;  // empty when valid
};

struct JuliaSetup {
  RationalMap map;       // as iterated (IterationMap): its frame is the iteration frame
  double lambda = 1.0;   // WithDetail's factor
  JuliaOptions julia;    // the root translation resolved, the rotation as the placement
  Vec3 box_min{0, 0, 0}, box_max{0, 0, 0};  // the sampling box, iteration frame
};

// Throws quijibo::Error on invalid options or when the translation by potential cannot be found.
JuliaSetup MakeJuliaSetup(const RationalMap& map, const JuliaSetupOptions& options);

// The same map for the generic engine (quaternion_map.h: IterateField, the map kinds): the
// iterated map's roots translated, the samples' offset and the capture in `iteration`
// (IterationOptions::offset, capture_radius; n and escape as given in `iteration`), and the
// normalized cube of the iteration frame. Its field is the mesh stage's log|q_n| at every point.
struct IteratedQuaternionMap {
  std::shared_ptr<const RationalQuaternionMap> map;
  IterationOptions iteration;
  Vec3 center{0, 0, 0};      // the iteration frame's box centre
  double half_extent = 0.0;  // fractal_radius / 2
};
// Throws quijibo::Error as MakeJuliaSetup does.
IteratedQuaternionMap MakeIteratedQuaternionMap(const RationalMap& map, const JuliaSetupOptions& options,
                                                IterationOptions iteration);

// The root translation alone, on the map as iterated (`iterated`: IterationMap of the input map).
Vec4 ResolveRootTranslation(const RationalMap& iterated, const JuliaSetupOptions& options);

}  // namespace quijibo
