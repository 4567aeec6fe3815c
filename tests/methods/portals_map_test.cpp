// Map kind "portals" (methods/maps/portals.cpp): portals in a map of any kind, as a map object.
#include <gtest/gtest.h>

#include "methods/map_kind.h"
#include "methods/portal.h"
#include "tests/methods/modulus_fixtures.h"
#include "tests/thrown_message.h"

namespace quijibo {
namespace {

using nlohmann::json;

KindMap ReadPortalsDoc(const json& doc) { return ReadKindMap(JsonReader(doc, "test"), "", ""); }

// The field of both maps on a 41^2 lattice of the plane over `box` (x0 y0 x1 y1): identical doubles.
// Returns how many samples are inside.
int SamePlaneField(const QuaternionMap& a, const QuaternionMap& b, const std::vector<double>& box,
                    const IterationOptions& it) {
  int inside = 0;
  for (int i = 0; i < 41; ++i)
    for (int j = 0; j < 41; ++j) {
      const Quat q{box[0] + (box[2] - box[0]) * (i + 0.5) / 41, box[1] + (box[3] - box[1]) * (j + 0.5) / 41, 0, 0};
      const double fa = IterateField(a, q, it), fb = IterateField(b, q, it);
      EXPECT_EQ(fa, fb) << q.w << " " << q.x;
      inside += fa < 0;
    }
  return inside;
}

TEST(PortalsMap, WithoutPortalsItIsTheBaseMap) {
  const json base = {{"kind", "polynomial"}, {"c", {-1.0, 0.0}}};
  const KindMap km = ReadPortalsDoc({{"kind", "portals"}, {"base", base}});
  const KindMap b = ReadPortalsDoc(base);
  ASSERT_EQ(km.kind->name, "portals");
  // The base's iteration defaults, inside and region.
  EXPECT_EQ(km.iteration->iterations, b.iteration->iterations);
  EXPECT_EQ(km.iteration->escape_radius, b.iteration->escape_radius);
  EXPECT_TRUE(km.iteration->bounded);
  EXPECT_EQ(km.Region(true), b.Region(true));
  const int inside = SamePlaneField(*km.map, *b.map, km.Region(true), *km.iteration);
  EXPECT_GT(inside, 0);
  // An empty list is no portal too.
  const KindMap none = ReadPortalsDoc({{"kind", "portals"}, {"base", base}, {"portals", json::array()}});
  SamePlaneField(*none.map, *b.map, km.Region(true), *km.iteration);
}

// One portal (a feathered disc with a copy scaled, turned and moved, cut by the base set) in a 2D
// shape modulus, against PortalMap built from the same parts by hand.
TEST(PortalsMap, OnePortalIsThePortalMapBuiltDirectly) {
  const json portal = {{"mask", {{"type", "sphere"}, {"center", {0.3, 0.1, 0.0}}, {"radius", 0.15}}},
                       {"feather", 0.02},
                       {"strength", 0.9},
                       {"exclude_base", true},
                       {"transform",
                        {{"scale", 2.5},
                         {"rotation", {{"angle_deg", 30.0}, {"axis", {0, 0, 1}}}},
                         {"translation", {0.05, -0.02, 0.0}}}}};
  const json base = {{"kind", "modulus"},
                     {"target", "hexagram:size=0.6"},
                     {"alpha", 40.0},
                     {"beta", 0.01},
                     {"versor", {{"generate", {{"roots", 5}, {"seed", 2}}}}}};
  const KindMap km = ReadPortalsDoc({{"kind", "portals"}, {"base", base}, {"portals", {portal}}});

  const ModulusTarget target = AnalyticModulusTarget("hexagram:size=0.6");
  VersorGeneratorOptions g;
  g.roots = 5;
  g.seed = 2;
  g.box_min = target.box_min;
  g.box_max = target.box_max;
  Versor v;
  v.polynomial = GenerateVersorPolynomial(g);
  ShapeModulusOptions so;
  so.alpha = 40.0;
  so.beta = 0.01;
  auto sm = std::make_shared<ShapeModulusMap>(target, v, so);
  Portal p;
  p.mask.type = Mask::Type::kSphere;
  p.mask.center = {0.3, 0.1, 0.0};
  p.mask.radius = 0.15;
  p.feather = 0.02;
  p.strength = 0.9;
  p.exclude_base = true;
  p.transform.center = p.mask.center;
  p.transform.scale = 2.5;
  p.transform.angle_deg = 30.0;
  p.transform.translation = {0.05, -0.02, 0.0};
  const PortalMap direct(sm, {p}, [phi = target.phi](const Quat& q) { return phi({q.w, q.x, q.y}) + 0.01; });

  // The shape modulus' defaults and region (2D target: the plane).
  EXPECT_EQ(km.iteration->iterations, 3);
  const std::vector<double> box = km.Region(true);
  EXPECT_EQ(box, ModulusRegion(target, true));
  SamePlaneField(*km.map, direct, box, *km.iteration);
  // The portal changes the set: some samples in its disc differ from the base map's.
  int changed = 0;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      const Quat q{0.15 + 0.3 * i / 20, -0.05 + 0.3 * j / 20, 0, 0};
      changed += (IterateField(*km.map, q, *km.iteration) < 0) != (IterateField(*sm, q, *km.iteration) < 0);
    }
  EXPECT_GT(changed, 0);
}

TEST(PortalsMap, BadKeysNameTheirJsonPointer) {
  const json base = {{"kind", "polynomial"}, {"c", {-1.0, 0.0}}};
  auto message = [](const json& doc) { return testing::ThrownMessage([&] { ReadPortalsDoc(doc); }); };
  EXPECT_NE(message({{"kind", "portals"}}).find("/base"), std::string::npos);
  EXPECT_NE(message({{"kind", "portals"}, {"base", {{"kind", "polynomial"}}}}).find("/base/c"), std::string::npos);
  EXPECT_NE(message({{"kind", "portals"}, {"base", base}, {"portals", {{{"mask", {{"type", "disc"}}}}}}})
                .find("/portals/0/mask/type"),
            std::string::npos);
  EXPECT_NE(message({{"kind", "portals"}, {"base", base}, {"portal", json::array()}}).find("portal"),
            std::string::npos);
}

}  // namespace
}  // namespace quijibo
