// `quijibo mesh` and `quijibo picture` as a user meets them: outputs, one-line errors, no partial
// output on bad input.
#include <gtest/gtest.h>

#include "quijibo_command.h"
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include "quijibo/julia_batch.h"

namespace quijibo {
namespace {

using quijibo::testing::CommandResult;
using quijibo::testing::RunQuijibo;

class JuliaCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("quijibo_julia_cli_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    ASSERT_EQ(RunQuijibo("map random --top 6 --bottom 4 --seed 3 --center-on sphere --target-resolution 12 -o " +
                      Path("map.json"))
                  .code,
              0);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  bool Exists(const std::string& name) const { return std::filesystem::exists(Path(name)); }
  std::filesystem::path dir_;
};

TEST_F(JuliaCli, MeshWritesPlyObjVdbAndASummary) {
  // Output folders that do not exist yet are created.
  const CommandResult r = RunQuijibo("mesh " + Path("map.json") + " -o " + Path("new/m.ply") + " --obj " + Path("m.obj") +
                        " --vdb " + Path("vdb/m.vdb") + " -r 24 -n 2 --frame fractal");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GT(j["triangles"].get<int>(), 10);
  EXPECT_EQ(j["evaluations"]["non_finite"].get<int>(), 0);
  EXPECT_EQ(j["box_frame"], "fractal");
  EXPECT_TRUE(Exists("new/m.ply") && Exists("m.obj") && Exists("vdb/m.vdb"));
  const CommandResult p =
      RunQuijibo("picture render " + Path("new/m.ply") + " -o " + Path("pics/r.png") + " --size 64 --views 2");
  EXPECT_EQ(p.code, 0) << p.out;
  EXPECT_TRUE(Exists("pics/r.png"));
  const CommandResult f = RunQuijibo("picture field " + Path("map.json") + " -o " + Path("f.png") + " --size 32 --axis y");
  EXPECT_EQ(f.code, 0) << f.out;
  ASSERT_EQ(RunQuijibo("target sphere -r 16 -o " + Path("t.qgrid")).code, 0);
  const CommandResult s = RunQuijibo("picture slice " + Path("map.json") + " --target " + Path("t.qgrid") + " -o " +
                        Path("s.png") + " --size 32 -n 1");
  ASSERT_EQ(s.code, 0) << s.out;
  const double agreement = nlohmann::json::parse(s.out)["agreement"].get<double>();
  EXPECT_GT(agreement, 0.0);
  EXPECT_LE(agreement, 1.0);
}

// --stream: the PLY and the .vdb's field grid are the in-memory ones (byte for byte; the .vdb but its
// random UUID), in the user frame with a rotation (the output transform) and in double; the summary's
// counts the same; what it cannot write is refused before meshing, with nothing written.
TEST_F(JuliaCli, MeshStreamWritesTheSameFiles) {
  auto slurp = [&](const std::string& name) {
    std::ifstream in(Path(name), std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string common = " -r 40 -n 2 --tile 8 --rotate 0,1,1,30 --vdb-grids field";
  for (const std::string& extra : {std::string(), std::string(" --ply-double")}) {
    SCOPED_TRACE(extra);
    const CommandResult m = RunQuijibo("mesh " + Path("map.json") + " -o " + Path("m.ply") + " --vdb " + Path("m.vdb") +
                                       common + extra);
    ASSERT_EQ(m.code, 0) << m.out;
    const CommandResult s = RunQuijibo("mesh " + Path("map.json") + " -o " + Path("s/s.ply") + " --vdb " +
                                       Path("s/s.vdb") + common + extra + " --stream");
    ASSERT_EQ(s.code, 0) << s.out;
    const auto jm = nlohmann::json::parse(m.out), js = nlohmann::json::parse(s.out);
    EXPECT_GT(jm["triangles"].get<int>(), 100);
    for (const char* key : {"triangles", "vertices", "components", "open_edges", "specks_removed", "boundary_edges",
                            "non_manifold_edges", "band_nodes"})
      EXPECT_EQ(js[key], jm[key]) << key;
    EXPECT_EQ(js["streamed"]["index_type"], "int");
    EXPECT_FALSE(jm.contains("streamed"));
    const std::string a = slurp("m.ply"), b = slurp("s/s.ply");
    EXPECT_EQ(js["streamed"]["bytes"].get<std::size_t>(), b.size());
    EXPECT_TRUE(a == b) << "the streamed PLY differs (" << a.size() << " and " << b.size() << " bytes)";
    const std::string va = slurp("m.vdb"), vb = slurp("s/s.vdb");
    ASSERT_GT(va.size(), 64u);
    EXPECT_TRUE(va.substr(64) == vb.substr(std::min<std::size_t>(64, vb.size())))
        << "the .vdb field grids differ after the header's UUID";
  }
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir_ / "s"), {}), 2) << "no scratch file left";
  struct Case {
    std::string args, expect;
  };
  for (const Case& c : {Case{" -o " + Path("x.obj"), "written as PLY"},
                        Case{" -o " + Path("x.ply") + " --obj " + Path("x.obj"), "no OBJ when streaming"},
                        Case{" -o " + Path("x.ply") + " --vdb " + Path("x.vdb"), "only the grid \"field\""}}) {
    const CommandResult r = RunQuijibo("mesh " + Path("map.json") + c.args + " -r 24 -n 2 --stream");
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << r.out;
    EXPECT_FALSE(Exists("x.ply") || Exists("x.obj") || Exists("x.vdb")) << c.args;
  }
}

TEST_F(JuliaCli, DetailAndTheReferenceFrameAreRecordedAndChangeOnlyTheNStepSet) {
  // A steep map (exponents x 60) whose one-step set is its n-step set; --detail widens the band.
  auto m = nlohmann::json::parse(std::ifstream(Path("map.json")));
  m["tau"] = m["tau"].get<double>() * 60, m["beta"] = m["beta"].get<double>() * 60, m["ln_C"] = m["ln_C"].get<double>() * 60;
  std::ofstream(Path("steep.json")) << m.dump();
  auto mesh_of = [&](const std::string& map, const std::string& extra, const std::string& out) {
    const CommandResult r = RunQuijibo("mesh " + Path(map) + " -o " + Path(out) + " -r 32 --frame fractal " + extra);
    EXPECT_EQ(r.code, 0) << r.out;
    return nlohmann::json::parse(r.out);
  };
  auto mesh = [&](const std::string& extra, const std::string& out) { return mesh_of("steep.json", extra, out); };
  const auto one = mesh("-n 1", "one.ply"), one_d = mesh("-n 1 --detail 20", "one_d.ply");
  EXPECT_EQ(one["triangles"], one_d["triangles"]);  // the one-step set stays
  const auto four = mesh("-n 4", "four.ply"), four_d = mesh("-n 4 --detail 20", "four_d.ply");
  EXPECT_NE(four["triangles"], four_d["triangles"]);
  EXPECT_EQ(four_d["iteration_frame"]["detail"].get<double>(), 20.0);
  EXPECT_LT(four_d["iteration_frame"]["lambda"].get<double>(), 1.0);
  const auto ref = mesh("-n 2 --iteration-frame reference --translate 0,0,0.1", "ref.ply");
  EXPECT_EQ(ref["iteration_frame"]["name"], "reference");
  EXPECT_EQ(ref["iteration_frame"]["fractal_radius"].get<double>(), 4.0);
  EXPECT_EQ(ref["julia"]["root_translation"][2].get<double>(), 0.1);
  // The translation by potential (on the steep map with a root at the origin, so the origin is
  // inside): reported, the one-step set kept, the n-step set changed; of --translate, only the
  // direction counts. An origin outside the set is refused with the reason.
  m["top"].push_back({{"root", {0.0, 0.0, 0.0, 0.0}}, {"exponent", 3.0}});
  std::ofstream(Path("ball.json")) << m.dump();
  auto ball = [&](const std::string& extra, const std::string& out) { return mesh_of("ball.json", extra, out); };
  const auto b1 = ball("-n 1", "b1.ply"), tp1 = ball("-n 1 --translate-potential -2", "tp1.ply");
  EXPECT_EQ(tp1["triangles"], b1["triangles"]);
  const auto b4 = ball("-n 4 --detail 20", "b4.ply"), tp = ball("-n 4 --detail 20 --translate-potential -2", "tp.ply");
  const double tz = tp["julia"]["root_translation"][2].get<double>();
  EXPECT_GT(tz, 0.0);
  EXPECT_EQ(tp["iteration_frame"]["translate_potential"].get<double>(), -2.0);
  EXPECT_TRUE(b4["iteration_frame"]["translate_potential"].is_null());
  EXPECT_EQ(tp["julia"]["root_translation"][0].get<double>(), 0.0);
  EXPECT_NE(tp["triangles"], b4["triangles"]);
  const auto tpx = ball("-n 4 --detail 20 --translate 0,0,7 --translate-potential -2", "tpx.ply");
  EXPECT_NEAR(tpx["julia"]["root_translation"][2].get<double>(), tz, 1e-12);
  for (const std::string& args : {std::string(" --translate 0,0,1,1 --translate-potential -2"),
                                  " --translate-potential -2 -o " + Path("out.ply")}) {
    const bool k = args.find("0,0,1,1") != std::string::npos;
    const CommandResult r = RunQuijibo("mesh " + Path(k ? "ball.json" : "steep.json") +
                                       (k ? " -o " + Path("k.ply") : std::string()) + args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.out.find(k ? "k component" : "not below the potential"), std::string::npos) << r.out;
  }
  EXPECT_FALSE(Exists("k.ply") || Exists("out.ply"));
  // Out of range: one line, no output.
  const CommandResult bad = RunQuijibo("mesh " + Path("steep.json") + " -o " + Path("bad.ply") + " --detail -1");
  EXPECT_NE(bad.code, 0);
  EXPECT_FALSE(Exists("bad.ply"));
}

TEST_F(JuliaCli, BadInputFailsWithOneLineAndNoOutput) {
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {"mesh " + Path("missing.json") + " -o " + Path("a.ply"), "missing.json"},
      {"mesh " + Path("map.json") + " -o " + Path("a.stl"), "must end in"},
      {"mesh " + Path("map.json") + " -o " + Path("a.ply") + " --box 1,1,1,0,2,2", "--box"},
      {"mesh " + Path("map.json") + " -o " + Path("a.ply") + " --rotate 0,0,0,10", "rotation"},
      {"mesh " + Path("map.json") + " -o " + Path("a.ply") + " --escape 0.5", "escape"},
      {"mesh " + Path("map.json") + " -o " + Path("a.ply") + " --tile 31", "tile"},
      {"mesh " + Path("map.json") + " -o " + Path("a.ply") + " --precision octuple", "octuple"},
      {"mesh " + Path("map.json") + " -o " + Path("map.json/a.ply"), "cannot create folder"},
      {"mesh " + Path("map.json") + " -o " + Path("new/a.stl"), "must end in"},
      {"picture render " + Path("map.json") + " -o " + Path("a.png"), "map.json"},
  };
  for (const Case& c : cases) {
    const CommandResult r = RunQuijibo(c.args);
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << " -> " << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  }
  EXPECT_FALSE(Exists("a.ply") || Exists("a.stl") || Exists("a.png") || Exists("new"));
}

// --kernel: the fused (default), vector and scalar kernels write the same PLY; `bench mesh` runs
// them and reports their throughput.
TEST_F(JuliaCli, KernelsGiveTheSameMeshAndBenchReportsBoth) {
  for (const char* k : {"vector", "scalar", "fused"}) {
    const CommandResult r = RunQuijibo("mesh " + Path("map.json") + " -o " + Path(std::string(k) + ".ply") +
                                       " -r 24 -n 2 --kernel " + k);
    ASSERT_EQ(r.code, 0) << r.out;
    EXPECT_EQ(nlohmann::json::parse(r.out)["kernel"], k);
  }
  std::ifstream a(Path("vector.ply"), std::ios::binary), b(Path("scalar.ply"), std::ios::binary);
  const std::string va((std::istreambuf_iterator<char>(a)), {}), sc((std::istreambuf_iterator<char>(b)), {});
  EXPECT_GT(va.size(), 1000u);
  EXPECT_EQ(va, sc);
  std::ifstream f(Path("fused.ply"), std::ios::binary);
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(f)), {}), sc);
  EXPECT_NE(RunQuijibo("mesh " + Path("map.json") + " -o " + Path("x.ply") + " --kernel simd").code, 0);

  const CommandResult r = RunQuijibo("bench mesh " + Path("map.json") + " --resolutions 16 -n 2 --markdown " +
                                     Path("bench.md"));
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out.substr(r.out.find("{\n")));
  ASSERT_EQ(j["results"].size(), 3u);
  EXPECT_EQ(j["results"][0]["kernel"], "scalar");
  EXPECT_EQ(j["results"][1]["kernel"], "vector");
  EXPECT_EQ(j["results"][2]["kernel"], "fused");
  EXPECT_EQ(j["results"][0]["triangles"], j["results"][1]["triangles"]);
  EXPECT_EQ(j["results"][0]["triangles"], j["results"][2]["triangles"]);
  for (const auto& c : j["results"]) {
    EXPECT_GT(c["factor_evaluations_per_second"].get<double>(), 0) << c;
    EXPECT_GT(c["peak_rss_mb"].get<double>(), 0) << c;
  }
  EXPECT_TRUE(j.contains("vector_isa"));
  EXPECT_TRUE(Exists("bench.md"));
}

// `bench mesh` takes the mesh stage's settings (an intricate set: detail, translation, frame) and
// compares the kernels' sets by volume IoU at random points.
TEST_F(JuliaCli, BenchMeshTakesTheMeshStageSettings) {
  const std::string common = "bench mesh " + Path("map.json") + " --resolutions 16 -n 3 --kernel vector,fused ";
  const CommandResult plain = RunQuijibo(common);
  ASSERT_EQ(plain.code, 0) << plain.out;
  const CommandResult r = RunQuijibo(common + "--detail 2 --translate 0,0,0.1 --iteration-frame reference "
                                              "--bisection-steps 3 --bisection-interpolate --compare-points 3000");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto p = nlohmann::json::parse(plain.out.substr(plain.out.find("{\n")));
  const auto j = nlohmann::json::parse(r.out.substr(r.out.find("{\n")));
  ASSERT_EQ(j["results"].size(), 2u);
  EXPECT_EQ(j["results"][1]["kernel"], "fused");
  EXPECT_EQ(j["mesh_settings"]["detail"].get<double>(), 2.0);
  EXPECT_EQ(j["mesh_settings"]["iteration_frame"], "reference");
  EXPECT_EQ(j["results"][0]["root_translation"][2].get<double>(), 0.1);
  // The settings reach the mesher: another set, fewer bisection evaluations per crossing edge.
  EXPECT_NE(j["results"][0]["applications"], p["results"][0]["applications"]);
  EXPECT_LT(j["results"][0]["bisection"].get<double>() / j["results"][0]["vertices"].get<double>(),
            p["results"][0]["bisection"].get<double>() / p["results"][0]["vertices"].get<double>());
  ASSERT_EQ(j["set_agreement"].size(), 1u);
  const auto& a = j["set_agreement"][0];
  EXPECT_EQ(a["kernel"], "fused");
  EXPECT_EQ(a["points"].get<int>(), 3000);
  EXPECT_GT(a["inside"].get<int>(), 0);
  EXPECT_GE(a["volume_iou"].get<double>(), 0.99);
  EXPECT_NE(RunQuijibo(common + "--compare-points -1").code, 0);
}

// `bench mesh --kernel KERNEL:ISA` caps the instruction set of one case (A/B of AVX2 and AVX-512 in
// one run); the float kernel's set agrees with double's; --secant-steps reaches the mesher and is
// validated.
TEST_F(JuliaCli, BenchMeshInstructionSetCasesAndSecantSteps) {
  const std::string common = "bench mesh " + Path("map.json") + " --resolutions 16 -n 3 ";
  const CommandResult r = RunQuijibo(common + "--kernel vector:sse2,vector,float --secant-steps 1 --compare-points 3000");
  ASSERT_EQ(r.code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out.substr(r.out.find("{\n")));
  ASSERT_EQ(j["results"].size(), 3u);
  EXPECT_EQ(j["results"][0]["case"], "vector:sse2");
  EXPECT_EQ(j["results"][0]["kernel"], "vector");
  EXPECT_EQ(j["results"][0]["vector_isa"], "sse2");
  EXPECT_EQ(j["results"][1]["vector_isa"], VectorIsaName(BestVectorIsa()));
  EXPECT_EQ(j["results"][2]["kernel"], "float");
  // The same evaluations on every instruction set (the same field, to rounding).
  EXPECT_EQ(j["results"][0]["vertices"], j["results"][1]["vertices"]);
  ASSERT_EQ(j["set_agreement"].size(), 2u);
  EXPECT_GE(j["set_agreement"][0]["volume_iou"].get<double>(), 0.999);
  EXPECT_GE(j["set_agreement"][1]["volume_iou"].get<double>(), 0.99);
  EXPECT_NE(RunQuijibo(common + "--kernel vector:avx3").code, 0);
  EXPECT_NE(RunQuijibo(common + "--kernel vector --secant-steps 9").code, 0);
}

}  // namespace
}  // namespace quijibo
