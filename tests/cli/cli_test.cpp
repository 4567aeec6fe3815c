// The `quijibo` command as a user meets it: exit codes, one-line errors, JSON output.
#include <gtest/gtest.h>

#include "quijibo_command.h"
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "quijibo/rational_map.h"

namespace quijibo {
namespace {

using quijibo::testing::CommandResult;
using quijibo::testing::RunQuijibo;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("quijibo_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  void Write(const std::string& name, const std::string& text) const { std::ofstream(Path(name)) << text; }
  std::filesystem::path dir_;
};

TEST_F(CliTest, HelpListsTheSubcommands) {
  const CommandResult r = RunQuijibo("--help");
  EXPECT_EQ(r.code, 0);
  for (const char* s : {"energy", "map", "target", "bench"}) EXPECT_NE(r.out.find(s), std::string::npos) << s;
  EXPECT_EQ(RunQuijibo("energy --help").code, 0);
  EXPECT_NE(RunQuijibo("").code, 0);
  EXPECT_NE(RunQuijibo("no-such-command").code, 0);
}

TEST_F(CliTest, EnergyOfARandomMapIsJsonWithGradientAndDiagnostics) {
  const std::string map = Path("map.json");
  ASSERT_EQ(RunQuijibo("map random --top 5 --bottom 4 --seed 2 --center-on sphere --target-resolution 12 -o " + map).code, 0);
  const CommandResult r = RunQuijibo("energy -t sphere --target-resolution 12 -m " + map);
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["energy"].get<double>(), -1.0);
  EXPECT_LT(j["energy"].get<double>(), 1.0);
  EXPECT_EQ(j["gradient"]["top"].size(), 5u);
  EXPECT_EQ(j["gradient"]["bottom"].size(), 4u);
  EXPECT_EQ(j["overflowed_cells"], 0);
  EXPECT_EQ(j["cells"], 12 * 12 * 12);
  // The same energy from the cached evaluator in long double, via a .qgrid target file.
  const std::string grid = Path("sphere.qgrid");
  ASSERT_EQ(RunQuijibo("target sphere -r 12 -o " + grid).code, 0);
  const CommandResult c = RunQuijibo("energy -t " + grid + " -m " + map + " -e cached -p long-double");
  ASSERT_EQ(c.code, 0) << c.out;
  EXPECT_NEAR(nlohmann::json::parse(c.out)["energy"].get<double>(), j["energy"].get<double>(), 1e-13);
}

TEST_F(CliTest, BadInputGetsOneClearLineAndNonZeroExit) {
  auto expect_error = [&](const std::string& args, const std::string& needle) {
    const CommandResult r = RunQuijibo(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.out.find(needle), std::string::npos) << args << "\n got: " << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  };
  RationalMap m;
  m.top_roots = {{0.5, 0, 0, 0}};
  m.top_exponents = {1.0};
  const std::string good = Path("good.json");
  WriteMap(good, m);

  expect_error("energy -t sphere -m " + Path("missing.json"), "missing.json");
  Write("syntax.json", "{\n \"format\": \"quijibo-map\",\n \"version\": 1,\n oops\n}");
  expect_error("energy -t sphere -m " + Path("syntax.json"), "syntax.json:4:");
  std::string text = MapToJson(m).dump();
  Write("negative.json", nlohmann::json::parse(text).dump().replace(text.find("\"exponent\":1.0"), 14, "\"exponent\":-1"));
  expect_error("energy -t sphere -m " + Path("negative.json"), "/top/0/exponent: expected a number >= 0");
  auto j = MapToJson(m);
  j["tua"] = 1.0;
  Write("typo.json", j.dump());
  expect_error("energy -t sphere -m " + Path("typo.json"), "did you mean \"tau\"");
  j = MapToJson(m);
  j["ln_C"] = "zero";
  Write("type.json", j.dump());
  expect_error("energy -t sphere -m " + Path("type.json"), "/ln_C: expected a number, found string");
  expect_error("energy -t cube -m " + good, "unknown analytic target \"cube\"");
  expect_error("energy -t sphere:radius=-1 -m " + good, "radius must be > 0");
  expect_error("energy -t sphere -m " + good + " -p float", "loglinear evaluator runs in double only");
  expect_error("energy -t sphere -m " + good + " --target-resolution 0", "target-resolution");
  expect_error("energy -t " + Path("nothing.qgrid") + " -m " + good, "nothing.qgrid");
  Write("bad.qgrid", "not a grid");
  expect_error("energy -t " + Path("bad.qgrid") + " -m " + good, "not a .qgrid file");
  expect_error("energy -t sphere:radius=9 --target-resolution 8 -m " + good, "no cell outside");
}

TEST_F(CliTest, FailedWritesLeaveNoFileBehind) {
  Write("file", "not a folder");
  const std::string out = Path("file/dir/map.json");  // its folder cannot be created
  const CommandResult r = RunQuijibo("map random --top 2 --bottom 2 -o " + out);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("cannot create folder"), std::string::npos) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_FALSE(std::filesystem::exists(out));
}

// Output folders are created (after the inputs were read), by every command alike.
TEST_F(CliTest, OutputFoldersAreCreated) {
  ASSERT_EQ(RunQuijibo("map random --top 2 --bottom 2 -o " + Path("new/maps/map.json")).code, 0);
  EXPECT_TRUE(std::filesystem::exists(Path("new/maps/map.json")));
  ASSERT_EQ(RunQuijibo("target sphere -r 8 -o " + Path("new/grids/sphere.qgrid")).code, 0);
  EXPECT_TRUE(std::filesystem::exists(Path("new/grids/sphere.qgrid")));
  // Bad input first: no folder.
  EXPECT_NE(RunQuijibo("energy -t cube -m " + Path("new/maps/map.json") + " -o " + Path("never/e.json")).code, 0);
  EXPECT_FALSE(std::filesystem::exists(Path("never")));
}

// -q/--quiet is accepted after any subcommand as well as before it.
TEST_F(CliTest, QuietAfterTheSubcommand) {
  const std::string map = Path("map.json");
  const CommandResult a = RunQuijibo("map random --top 2 --bottom 2 -o " + map + " -q");
  EXPECT_EQ(a.code, 0) << a.out;
  const CommandResult b = RunQuijibo("energy -t sphere --target-resolution 8 -m " + map + " --quiet");
  EXPECT_EQ(b.code, 0) << b.out;
  EXPECT_NE(RunQuijibo("optimize --help").out.find("--quiet"), std::string::npos);
}

TEST_F(CliTest, RandomMapsAreDeterministic) {
  ASSERT_EQ(RunQuijibo("map random --top 30 --bottom 20 --seed 9 -o " + Path("a.json")).code, 0);
  ASSERT_EQ(RunQuijibo("map random --top 30 --bottom 20 --seed 9 -o " + Path("b.json")).code, 0);
  std::ifstream a(Path("a.json")), b(Path("b.json"));
  const std::string sa((std::istreambuf_iterator<char>(a)), {}), sb((std::istreambuf_iterator<char>(b)), {});
  EXPECT_EQ(sa, sb);
  EXPECT_EQ(ReadMap(Path("a.json")).top_count(), 30);
}

// A map and a target grid in different frames (the map's origin moved and its fractal radius
// doubled, as a `monopoles` map with the origin inside and the trap scale against an `sdf mesh`
// grid with the default centre): every command that reads both refuses with one line naming both
// files and the fields that differ, and writes nothing. The same map in the target's frame passes.
TEST_F(CliTest, EveryCommandWithAMapAndATargetRefusesAFrameMismatch) {
  const std::string t = Path("t.qgrid"), same = Path("same.json"), other = Path("other.json");
  ASSERT_EQ(RunQuijibo("target sphere -r 12 -o " + t).code, 0);
  ASSERT_EQ(RunQuijibo("map random --top 3 --bottom 2 --seed 1 --center-on " + t + " -o " + same).code, 0);
  nlohmann::json m = nlohmann::json::parse(std::ifstream(same));
  m["frame"]["origin"] = {0.4, 0.5, 0.5};
  m["frame"]["fractal_radius"] = 8.0;
  Write("other.json", m.dump());
  const std::vector<std::string> commands = {
      "energy -t T -m M",
      "optimize -t T -m M -o " + Path("opt") + " --schedule '8(V)'",
      "fidelity -m M -t T --lattice 8 -n 1",
      "picture slice M --target T -o " + Path("s.png") + " --size 16 -n 1",
      "compare --target T --map M -r 8 --samples 200 --png-size 16 -o " + Path("cmp"),
      "bench band --target T --map M --grids 8 --iterations 1 --form-iterations 0 --json " + Path("band.json"),
  };
  auto with = [](std::string c, const std::string& target, const std::string& map) {
    for (std::size_t at; (at = c.find(" T")) != std::string::npos && (at + 2 == c.size() || c[at + 2] == ' ');)
      c.replace(at + 1, 1, target);
    for (std::size_t at; (at = c.find(" M")) != std::string::npos && (at + 2 == c.size() || c[at + 2] == ' ');)
      c.replace(at + 1, 1, map);
    return c;
  };
  for (const std::string& c : commands) {
    const CommandResult r = RunQuijibo(with(c, t, other));
    EXPECT_NE(r.code, 0) << c << ": " << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << c << ": " << r.out;
    for (const std::string& piece :
         {t + ": the target's frame (no frame file: the default) is not the map's (" + other + ")",
          std::string("origin (0.5, 0.5, 0.5) vs (0.4, 0.5, 0.5)"), std::string("fractal_radius 4 vs 8")})
      EXPECT_NE(r.out.find(piece), std::string::npos) << c << ": " << r.out;
    for (const char* out : {"opt", "s.png", "cmp", "band.json"})
      EXPECT_FALSE(std::filesystem::exists(Path(out))) << c << ": " << out;
  }
  EXPECT_EQ(RunQuijibo(with(commands[0], t, same)).code, 0);
  EXPECT_EQ(RunQuijibo(with(commands[2], t, same)).code, 0);
  // A grid whose frame file records the map's frame passes; the map in the default frame does not.
  Write("t.frame.json", R"({"format": "quijibo-frame", "version": 1, "fractal_radius": 8, "padding": 0.125,
                            "scale": 1, "translation": [0, 0, 0], "origin": [0.4, 0.5, 0.5]})");
  EXPECT_EQ(RunQuijibo(with(commands[0], t, other)).code, 0);
  const CommandResult r = RunQuijibo(with(commands[0], t, same));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("(" + Path("t.frame.json") + ") is not the map's"), std::string::npos) << r.out;
}

// `quijibo julia`, the experiment method "julia" and portal scenes over a map object: the engine
// takes any map kind (methods/map_kind.h) from the command line and from experiments.
class MapKindsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("quijibo_map_kinds_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  void Write(const std::string& name, const nlohmann::json& j) const { std::ofstream(Path(name)) << j.dump(1); }
  std::filesystem::path dir_;
};

TEST_F(MapKindsCli, JuliaDrawsAndMeshesAPolynomial) {
  Write("basilica.json", {{"kind", "polynomial"}, {"c", {-1.0, 0.0}}});
  const CommandResult png = RunQuijibo("julia " + Path("basilica.json") + " -o " + Path("b.png") + " --png-size 64");
  ASSERT_EQ(png.code, 0) << png.out;
  const nlohmann::json r = nlohmann::json::parse(png.out);
  EXPECT_EQ(r["kind"], "polynomial");
  EXPECT_EQ(r["result"]["iterations"], 20);  // the kind's default
  EXPECT_GT(r["result"]["inside_pixels"].get<int>(), 64 * 64 / 8);
  EXPECT_TRUE(std::filesystem::exists(Path("b.png")));
  Write("ball.json", {{"kind", "polynomial"}, {"c", {0.0, 0.0, 0.0, 0.0}}});
  const CommandResult ply = RunQuijibo("julia " + Path("ball.json") + " -o " + Path("b.ply") + " -r 24");
  ASSERT_EQ(ply.code, 0) << ply.out;
  EXPECT_GT(nlohmann::json::parse(ply.out)["result"]["triangles"].get<int>(), 100);
}

TEST_F(MapKindsCli, BadKindsAreRefusedWithThePointer) {
  Write("bad.json", {{"kind", "polynomial"}, {"c", {1.0}}});
  const CommandResult r = RunQuijibo("julia " + Path("bad.json") + " -o " + Path("b.png"));
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("/c: expected 2 (complex) or 4"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(Path("b.png")));
  Write("e.json", {{"method", "julia"}, {"julia", {{"map", {{"kind", "cubic"}}}}}});
  const CommandResult e = RunQuijibo("run --check " + Path("e.json"));
  EXPECT_EQ(e.code, 1);
  EXPECT_NE(e.out.find("/julia/map/kind"), std::string::npos) << e.out;
}

TEST_F(MapKindsCli, ExperimentAndPortalSceneTakeAMapObject) {
  Write("j.json", {{"method", "julia"},
                   {"julia", {{"map", {{"kind", "polynomial"}, {"c", {-1.0, 0.0}}}}, {"output", {{"png_size", 32}}}}}});
  const CommandResult j = RunQuijibo("run " + Path("j.json") + " --quiet --out " + Path("j"));
  ASSERT_EQ(j.code, 0) << j.out;
  EXPECT_TRUE(std::filesystem::exists(Path("j/julia/julia.png")));
  Write("p.json", {{"method", "portal"},
                   {"portal",
                    {{"spec",
                      {{"format", "quijibo-portals"},
                       {"version", 1},
                       {"map", {{"kind", "polynomial"}, {"c", {-1.0, 0.0}}}},
                       {"dimension", 2},
                       {"portals", {{{"mask", {{"type", "sphere"}, {"center", {1.8, 0.0, 0.0}}, {"radius", 0.1}}},
                                     {"transform", {{"scale", 15}}}}}}}},
                     {"output", {{"png_size", 32}}}}}});
  const CommandResult p = RunQuijibo("run " + Path("p.json") + " --quiet --out " + Path("p"));
  ASSERT_EQ(p.code, 0) << p.out;
  const nlohmann::json report = nlohmann::json::parse(std::ifstream(Path("p/portal/portal.json")));
  // The kind's defaults: n 20 (as a spec's own default) and escape radius 4 (a spec's is 20).
  EXPECT_EQ(report["result"]["iterations"], 20);
  EXPECT_EQ(report["result"]["escape_radius"], 4.0);
}

TEST_F(MapKindsCli, JuliaTakesAQuijiboMapAsKindRational) {
  ASSERT_EQ(RunQuijibo("map random --top 6 --bottom 4 --seed 3 --center-on sphere --target-resolution 12 -o " +
                       Path("map.json")).code, 0);
  Write("r.json", {{"kind", "rational"}, {"file", "map.json"}, {"detail", 0}});
  const CommandResult r = RunQuijibo("julia " + Path("r.json") + " -o " + Path("r.png") + " --png-size 48");
  ASSERT_EQ(r.code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "rational");
  EXPECT_EQ(j["result"]["iterations"], 4);  // the mesh stage's n and escape radius
  EXPECT_EQ(j["result"]["escape_radius"], 2000.0);
  EXPECT_EQ(j["result"]["inside"], "|q_n| < 1");
  const int inside = j["result"]["inside_pixels"].get<int>();
  EXPECT_GT(inside, 0);
  EXPECT_LT(inside, 48 * 48);
}

// The gallery's experiments (docs/gallery.md) stay valid: each one checks as shipped.
TEST(GalleryExperiments, EachChecks) {
  int checked = 0;
  for (const auto& e : std::filesystem::directory_iterator(std::string(QUIJIBO_SOURCE_DIR) + "/experiments/gallery")) {
    if (e.path().extension() != ".json") continue;
    // Portal specs and versor polynomials of the gallery's scripts carry a "format"; experiments do not.
    if (nlohmann::json::parse(std::ifstream(e.path())).contains("format")) continue;
    const CommandResult r = RunQuijibo("run --check " + e.path().string());
    EXPECT_EQ(r.code, 0) << e.path() << "\n" << r.out;
    ++checked;
  }
  EXPECT_GE(checked, 5);
}

}  // namespace
}  // namespace quijibo
