// Map kind "rational" (methods/maps/rational.cpp): a QUIJIBO map through the engine's interface,
// against the mesh stage's own iteration (JuliaMap on the same iterated map and options), with and
// without a root translation.
#include <gtest/gtest.h>

#include <cmath>

#include "methods/map_kind.h"
#include "quijibo/julia.h"
#include "quijibo/julia_setup.h"
#include "tests/mesh/mesh_fixtures.h"
#include "tests/thrown_message.h"

namespace quijibo {
namespace {

using testing::SmallSetMap;
using testing::TempDir;
using testing::ThrownMessage;

KindMap Rational(nlohmann::json doc) { return ReadKindMap(JsonReader(doc, "test"), "", ""); }

// The engine's field (IterateField with the kind's map and iteration) against JuliaMap's
// log|q_n| for the setup the mesh stage makes from the same settings, on a 17^3 lattice of the
// kind's region; returns the nodes whose inside differs between the two, and checks the values.
int CompareWithTheMeshStage(const KindMap& km, const JuliaSetup& setup) {
  const JuliaMap<double> julia(setup.map, setup.julia);
  int differ = 0, compared = 0;
  const int n = 17;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Vec3 p{km.center[0] - km.half_extent + 2 * km.half_extent * i / (n - 1),
                     km.center[1] - km.half_extent + 2 * km.half_extent * j / (n - 1),
                     km.center[2] - km.half_extent + 2 * km.half_extent * k / (n - 1)};
        const double a = julia.At(p).log_modulus;
        const double b = IterateField(*km.map, Quat{p[0], p[1], p[2], 0.0}, *km.iteration);
        if (!std::isfinite(a)) continue;
        differ += (a < 0) != (b < 0);
        // The engine forms q_n = e^{log|q_n|} versor: beyond |log| 300 its square under- or overflows.
        if (std::abs(a) > 300) continue;
        ++compared;
        EXPECT_NEAR(b, a, 1e-9 * (1 + std::abs(a))) << p[0] << " " << p[1] << " " << p[2];
      }
  EXPECT_GT(compared, n * n * n / 2);
  return differ;
}

TEST(RationalMap, TranslatedKindIteratesAsTheMeshStage) {
  TempDir dir;
  const RationalMap map = SmallSetMap();
  WriteMap(dir.file("map.json"), map);
  JuliaSetupOptions setup;
  setup.detail = 0;
  setup.translate = std::vector<double>{0.1, -0.05, 0.2};
  setup.julia.capture_radius = 1e-3;
  const KindMap km = Rational({{"kind", "rational"},
                               {"file", dir.file("map.json")},
                               {"detail", 0},
                               {"translate", {0.1, -0.05, 0.2}},
                               {"capture", 1e-3}});
  ASSERT_TRUE(km.iteration);
  EXPECT_EQ(km.iteration->offset, Quat(0.1, -0.05, 0.2, 0.0));
  EXPECT_EQ(km.iteration->capture_radius, 1e-3);
  EXPECT_EQ(CompareWithTheMeshStage(km, MakeJuliaSetup(map, setup)), 0);
  // The translation is not ignored: the untranslated kind draws another set at n = 4.
  const KindMap plain = Rational({{"kind", "rational"}, {"file", dir.file("map.json")}, {"detail", 0}});
  EXPECT_EQ(plain.iteration->offset, Quat(0.0, 0.0, 0.0, 0.0));
  setup.translate.reset();
  setup.julia.capture_radius = 0;
  EXPECT_EQ(CompareWithTheMeshStage(plain, MakeJuliaSetup(map, setup)), 0);
  int moved = 0;
  for (double x = -1.5; x <= 1.5; x += 0.1)
    for (double y = -1.5; y <= 1.5; y += 0.1) {
      const Quat q{x, y, 0.1, 0.0};
      moved += (IterateField(*km.map, q, *km.iteration) < 0) != (IterateField(*plain.map, q, *plain.iteration) < 0);
    }
  EXPECT_GT(moved, 0);
  // The one-step set (portals' exclude_base) is the untranslated map's: L(p + t) with roots + t.
  for (const Quat q : {Quat{0.3, 0.1, -0.2, 0}, Quat{-0.7, 0.4, 0.5, 0}})
    EXPECT_NEAR(km.base_set(q), plain.base_set(q), 1e-12);
}

TEST(RationalMap, TranslationByPotentialIsTheMeshStages) {
  TempDir dir;
  const RationalMap map = SmallSetMap();
  WriteMap(dir.file("map.json"), map);
  const KindMap km = Rational({{"kind", "rational"},
                               {"file", dir.file("map.json")},
                               {"detail", 0},
                               {"translate", {0, 0, 1}},
                               {"translate_potential", -0.5}});
  const Vec4 t = TranslationForPotential(IterationMap(map, IterationFrame::kMap, 0.0), {0, 0, 1}, -0.5);
  EXPECT_GT(t[2], 0.0);
  EXPECT_EQ(km.iteration->offset, Quat(t[0], t[1], t[2], t[3]));
}

TEST(RationalMap, BadTranslationsAreRefusedAtTheirPointer) {
  TempDir dir;
  WriteMap(dir.file("map.json"), SmallSetMap());
  const nlohmann::json base = {{"kind", "rational"}, {"file", dir.file("map.json")}};
  nlohmann::json d = base;
  d["translate"] = {1, 2};
  EXPECT_NE(ThrownMessage([&] { Rational(d); }).find("/translate"), std::string::npos);
  d = base;
  d["translate_potential"] = 0.5;
  EXPECT_NE(ThrownMessage([&] { Rational(d); }).find("/translate_potential"), std::string::npos);
  d = base;
  d["capture"] = -1;
  EXPECT_NE(ThrownMessage([&] { Rational(d); }).find("/capture"), std::string::npos);
  // A potential deeper than the map reaches at the origin (L there is -1): the search's reason.
  d = base;
  d["detail"] = 0;
  d["translate_potential"] = -900;
  EXPECT_NE(ThrownMessage([&] { Rational(d); }).find("L at the iteration frame's origin"), std::string::npos);
}

}  // namespace
}  // namespace quijibo
