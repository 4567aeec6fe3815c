// `quijibo run`: a tiny experiment end to end, stage reuse by content hash, bad experiments (one
// clear line, non-zero exit, no results folder), kill and --resume, a read-only or full results
// folder.
// Tiny settings throughout (analytic torus, 20^3, a few iterations) so the suite stays fast.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <grp.h>
#include <unistd.h>

#include <fcntl.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "quijibo_command.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Slurp(const std::string& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

void Write(const std::string& p, const std::string& text) {
  std::ofstream(p) << text;
}

std::string TempDir(const std::string& name) {
  const auto d = fs::temp_directory_path() / ("quijibo_run_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

// Runs the binary with `args` (quijibo_command.h); stderr is collected in *err (when given). With
// `background`, returns at once with the pid. `max_file_bytes` (0: none) limits every file the
// child writes; `env` ("NAME=value") is added to the child's environment; `as_nobody`: run as the
// user nobody (when the test runs as root, who ignores file permissions).
int RunQ(const std::vector<std::string>& args, std::string* err = nullptr, pid_t* background = nullptr,
         rlim_t max_file_bytes = 0, const std::string& env = "", bool as_nobody = false) {
  quijibo::testing::LaunchOptions o;
  o.background = background;
  o.max_file_bytes = max_file_bytes;
  o.env = env;
  o.as_nobody = as_nobody;
  const auto r = quijibo::testing::RunQuijiboArgs(args, o);
  if (err) *err = r.err;
  return r.code;
}

bool HaveGnuplot() { return std::system("gnuplot --version > /dev/null 2>&1") == 0; }

// The tiny experiment: a torus, a random map, two short levels.
json Tiny() {
  return {{"name", "tiny"},
          {"seed", 3},
          {"target", {{"analytic", "torus"}, {"resolution", 20}}},
          {"initial", {{"kind", "random"}, {"top", 10}, {"bottom", 8}, {"root_radius", 1.0}}},
          {"optimizer",
           {{"schedule", "10(VF)20(VF)"}, {"max_iterations", {{"V", 8}, {"F", 15}}}, {"checkpoint_every", 5}}},
          {"mesh", {{"resolution", 20}, {"iterations", 1}}},
          {"intricate", {{"resolution", 20}}},
          {"pictures", {{"slice_size", 48}, {"render_size", 48}, {"render_views", 2}, {"triptych_size", 64}}},
          {"outputs", {{"plot", HaveGnuplot()}}}};
}

// The stages of run.json (a copy: iterating a member of a temporary would dangle).
json RunRecord(const std::string& out) { return json::parse(Slurp(out + "/run.json")); }

TEST(RunTest, ATinyExperimentRunsEndToEndAndIsReusedWhenUnchanged) {
  const std::string dir = TempDir("tiny");
  const std::string exp = dir + "/tiny.json", out = dir + "/results";
  Write(exp, Tiny().dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const char* f : {"experiment.resolved.json", "run.json", "report.md", "initial/target.qgrid",
                        "initial/target.frame.json", "initial/map.json", "optimized/map.json", "optimized/log.jsonl",
                        "optimized/summary.json", "optimized/checkpoint.json", "mesh/julia.ply", "mesh/julia.vdb",
                        "mesh/summary.json", "pictures/slice-n1.png", "pictures/render.png",
                        "intricate/summary.json", "triptych/triptych.json", "triptych/set.png", "triptych/triptych.png",
                        "report.html"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  if (HaveGnuplot()) {
    EXPECT_TRUE(fs::exists(out + "/plot/convergence.png"));
    EXPECT_TRUE(fs::exists(out + "/plot/convergence.svg"));
  }
  for (const auto& e : fs::recursive_directory_iterator(out))
    EXPECT_EQ(e.path().string().find(".partial"), std::string::npos) << e.path();
  const std::string report = Slurp(out + "/report.md");
  EXPECT_NE(report.find("10(VF)20(VF)"), std::string::npos);
  EXPECT_NE(report.find("pictures/render.png"), std::string::npos);
  const json resolved = json::parse(Slurp(out + "/experiment.resolved.json"));
  EXPECT_EQ(resolved["optimizer"][0]["backend"], "lbfgspp");  // defaults are filled in
  EXPECT_EQ(resolved["mesh"]["escape"], 2000.0);
  for (const json& s : json(RunRecord(out)["stages"])) EXPECT_EQ(s["status"], "ran") << s;
  const std::string map1 = Slurp(out + "/optimized/map.json");

  // Unchanged: every stage is reused.
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const json& s : json(RunRecord(out)["stages"])) EXPECT_EQ(s["status"], "reused") << s;
  EXPECT_NE(Slurp(out + "/report.md").find("reused"), std::string::npos);
  EXPECT_EQ(Slurp(out + "/optimized/map.json"), map1);

  // A meshing setting changes: the mesh and pictures run again, the optimization is reused.
  json changed = Tiny();
  changed["mesh"]["resolution"] = 22;
  Write(exp, changed.dump(1));
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const json& s : json(RunRecord(out)["stages"])) {
    const std::string name = s["stage"];
    EXPECT_EQ(s["status"], name == "mesh" || name == "pictures" || name == "triptych" ? "ran" : "reused") << s;
  }
  EXPECT_EQ(json::parse(Slurp(out + "/mesh/summary.json"))["resolution"], 22);

  // The mesh streamed to disk: the mesh stage runs again and writes the same julia.ply.
  const std::string ply22 = Slurp(out + "/mesh/julia.ply");
  changed["mesh"]["stream"] = true;
  changed["mesh"]["vdb"] = false;
  Write(exp, changed.dump(1));
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const json& s : json(RunRecord(out)["stages"])) {
    if (s["stage"] == "mesh") {
      EXPECT_EQ(s["status"], "ran") << s;
    }
  }
  EXPECT_EQ(Slurp(out + "/mesh/julia.ply"), ply22);
  EXPECT_FALSE(fs::exists(out + "/mesh/julia.vdb"));
  EXPECT_EQ(json::parse(Slurp(out + "/mesh/summary.json"))["streamed"]["index_type"], "int");
  fs::remove_all(dir);
}

TEST(RunTest, AMeshTargetGoesThroughTheMonopoleStage) {
  const std::string dir = TempDir("mesh");
  const std::string exp = dir + "/bunny.json", out = dir + "/results";
  const json e = {
      {"target", {{"mesh", std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj"}, {"resolution", 25}}},
      {"initial", {{"kind", "monopoles"}, {"candidates", 10000}, {"bem_elements", 600}, {"png_size", 64}}},
      {"optimizer", {{"schedule", "12(VF)"}, {"max_iterations", {{"V", 5}, {"F", 5}}}}},
      {"mesh", {{"enabled", false}}},
      {"pictures", {{"slice_size", 32}}},
      {"outputs", {{"plot", false}, {"report_html", false}}}};
  Write(exp, e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const char* f : {"initial/roots.ply", "initial/potential.png", "initial/monopoles.json", "optimized/map.json",
                        "pictures/slice-n1.png", "report.md"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  EXPECT_FALSE(fs::exists(out + "/report.html"));  // outputs.report_html off
  EXPECT_NE(Slurp(out + "/report.md").find("Initial guess"), std::string::npos);
  fs::remove_all(dir);
}

// Every run with a mesh target ends with the triptych (the 2015 paper's Fig. 1 for the user's mesh):
// the target, the set and the intricate surface rendered alike, report.md opening with them and a
// line of figures under each; the intricate surface a result like the mesh (PLY, VDB, summary).
TEST(RunTest, AMeshTargetEndsWithTheTriptych) {
  const std::string dir = TempDir("triptych");
  const std::string exp = dir + "/bunny.json", out = dir + "/results";
  // 100 roots: the log-kernel fit of the default 400 was two thirds of this test's time under the
  // sanitizers (53 of 75 s), and the triptych needs a bunny, not a good one.
  const json e = {{"target", {{"mesh", std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj"}, {"resolution", 25}}},
                  {"initial", {{"roots", 100}}},
                  {"optimizer", {{"schedule", "25(VF)"}, {"max_iterations", {{"V", 3}, {"F", 3}}}}},
                  {"mesh", {{"resolution", 32}}},
                  {"intricate", {{"resolution", 32}}},
                  {"pictures", {{"slice_size", 32}, {"render_size", 32}, {"triptych_size", 64}}},
                  {"outputs", {{"plot", false}}}};
  Write(exp, e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const char* f : {"intricate/julia.ply", "intricate/julia.vdb", "intricate/summary.json", "triptych/target.png",
                        "triptych/set.png", "triptych/intricate.png", "triptych/triptych.png", "triptych/triptych.json"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  const json t = json::parse(Slurp(out + "/triptych/triptych.json"));
  EXPECT_EQ(t["panels"], json({"target", "set", "intricate"}));
  // The intricate surface is translated (by the potential -2) and has more area than the set.
  const json is = json::parse(Slurp(out + "/intricate/summary.json"));
  EXPECT_EQ(is["iteration_frame"]["translate_potential"], -2.0);
  EXPECT_EQ(is["iteration_frame"]["detail"], 4.0);
  EXPECT_GT(std::abs(is["julia"]["root_translation"][2].get<double>()), 0.0);
  const json ms = json::parse(Slurp(out + "/mesh/summary.json"));
  EXPECT_GT(is["detail"]["area_ratio"].get<double>(), ms["detail"]["area_ratio"].get<double>());
  const json& f = t["figures"];
  EXPECT_GT(f["target"]["detail"]["box_dimension"].get<double>(), 1.5);
  EXPECT_GT(f["intricate"]["fidelity"]["n_step"]["closed_iou"].get<double>(), 0.3);
  EXPECT_EQ(f["intricate"]["fidelity"]["lattice"], 32);
  // report.md opens with the triptych: the three titles, the pictures, then the Quality section.
  const std::string report = Slurp(out + "/report.md");
  const auto a = report.find("(a) the target"), pics = report.find("triptych/intricate.png"),
             q = report.find("## Quality");
  ASSERT_NE(a, std::string::npos) << report;
  EXPECT_NE(report.find("(c) intricate, detail 4.00, L = -2.00 at −t"), std::string::npos) << report;
  EXPECT_LT(a, pics);
  EXPECT_LT(pics, q);
  EXPECT_NE(report.find("closed IoU"), std::string::npos);
  // Switched off, neither the intricate surface nor the triptych is made.
  json off = e;
  off["intricate"] = {{"enabled", false}};
  off["pictures"]["triptych"] = false;
  Write(exp, off.dump(1));
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  EXPECT_FALSE(fs::exists(out + "/intricate"));
  EXPECT_FALSE(fs::exists(out + "/triptych"));
  EXPECT_EQ(Slurp(out + "/report.md").find("(a) the target"), std::string::npos);
  fs::remove_all(dir);
}

struct BadCase {
  std::string name, text, expect;  // expect: a piece of the one-line message
};

TEST(RunTest, BadExperimentsGiveOneClearLineAndNoResultsFolder) {
  const std::string dir = TempDir("bad");
  const std::string torus = R"("target": {"analytic": "torus", "resolution": 20})";
  const std::vector<BadCase> cases = {
      {"syntax", "{\"name\": \"x\",", ":1:"},
      {"nan", R"({"target": {"analytic": "torus", "resolution": NaN}})", ":1:"},
      {"not-object", "[1, 2]", "expected a JSON object"},
      {"unknown-key", "{" + torus + R"(, "optimiser": {}})", "/optimiser: unknown key (did you mean \"optimizer\"?)"},
      {"unknown-nested", "{" + torus + R"(, "mesh": {"resolutoin": 64}})", "/mesh/resolutoin"},
      {"clipped-key", "{" + torus + R"(, "optimizer": {"max_iters": {"F": 5}}})",
       "/optimizer/max_iters: unknown key (did you mean \"max_iterations\"?)"},
      {"wrong-type", R"({"target": {"analytic": "torus", "resolution": "big"}})", "/target/resolution: expected an integer"},
      {"negative-res", R"({"target": {"analytic": "torus", "resolution": -5}})", "/target/resolution"},
      {"zero-res", R"({"target": {"analytic": "torus", "resolution": 0}})", "/target/resolution"},
      {"huge-res", R"({"target": {"analytic": "torus", "resolution": 100000000}})", "/target/resolution"},
      {"mesh-res", "{" + torus + R"(, "mesh": {"resolution": -1}})", "/mesh/resolution"},
      {"stream-vdb", "{" + torus + R"(, "mesh": {"stream": true}})", "/mesh/stream: a streamed mesh needs \"vdb\": false"},
      {"empty-schedule", "{" + torus + R"(, "optimizer": {"schedule": ""}})", "/optimizer/schedule"},
      {"empty-levels", "{" + torus + R"(, "optimizer": {"schedule": {"levels": []}}})", "/optimizer/schedule/levels"},
      {"bad-notation", "{" + torus + R"j(, "optimizer": {"schedule": "25(VXF)"}})j", "/optimizer/schedule"},
      {"missing-mesh", R"({"target": {"mesh": "no-such-mesh.obj"}})", "/target/mesh: no such file"},
      {"no-target", R"({"name": "x"})", "/target"},
      {"two-targets", R"({"target": {"analytic": "torus", "mesh": "a.obj"}})", "exactly one"},
      {"precision", "{" + torus + R"(, "optimizer": {"evaluator": "band", "precision": "long-double"}})",
       "/optimizer/precision"},
      {"method", "{" + torus + R"(, "method": "quijbo"})", "/method"},
      {"padding", R"({"target": {"analytic": "torus", "padding": 0.7}})", "/target/padding"},
      {"frame-scale-analytic", R"({"target": {"analytic": "torus", "frame_scale": "trap"}})",
       "/target/frame_scale: applies only to QUIJIBO mesh targets with \"origin\": \"inside\""},
      {"frame-scale-center", R"({"target": {"mesh": "a.obj", "origin": "center", "frame_scale": "trap"}})",
       "/target/frame_scale: applies only"},
  };
  for (const BadCase& c : cases) {
    const std::string exp = dir + "/" + c.name + ".json", out = dir + "/out-" + c.name;
    Write(exp, c.text);
    std::string err;
    EXPECT_NE(RunQ({"run", exp, "--out", out}, &err), 0) << c.name;
    EXPECT_NE(err.find(c.expect), std::string::npos) << c.name << ": " << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << c.name << ": " << err;
    EXPECT_EQ(err.rfind("quijibo: error: ", 0), 0u) << c.name << ": " << err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  std::string err;
  EXPECT_NE(RunQ({"run", dir + "/missing.json", "--out", dir + "/out-missing"}, &err), 0);
  EXPECT_NE(err.find("no such file"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/out-missing"));
  // A mesh that is not a mesh: found only when the initial stage reads it; nothing is left behind.
  Write(dir + "/garbage.obj", "this is not a mesh\n");
  Write(dir + "/garbage.json", R"({"target": {"mesh": "garbage.obj", "resolution": 16}})");
  EXPECT_NE(RunQ({"run", dir + "/garbage.json", "--out", dir + "/out-garbage"}, &err), 0);
  EXPECT_NE(err.find("garbage.obj"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir + "/out-garbage")) << err;
  fs::remove_all(dir);
}

TEST(RunTest, AReadOnlyResultsFolderIsAClearError) {
  const std::string dir = TempDir("readonly");
  const std::string exp = dir + "/tiny.json";
  Write(exp, Tiny().dump(1));
  const std::string out = dir + "/locked";
  fs::create_directories(out);
  ::chmod(out.c_str(), 0555);
  // root ignores permissions: then the command runs as the user nobody.
  const bool root = ::geteuid() == 0;
  std::string err;
  EXPECT_NE(RunQ({"run", exp, "--out", out + "/sub"}, &err, nullptr, 0, "", root), 0);
  EXPECT_NE(err.find("not writable (Permission denied)"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out + "/sub"));
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  ::chmod(out.c_str(), 0755);
  fs::remove_all(dir);
}

// A Julia set whose surface misses the box is a result, not a failure: the run finishes, the report
// says so, and there is no mesh file and no render.
TEST(RunTest, AJuliaSetWithoutSurfaceIsReportedNotFatal) {
  const std::string dir = TempDir("nosurface");
  const std::string exp = dir + "/tiny.json", out = dir + "/results";
  json e = Tiny();
  e["optimizer"]["schedule"] = "10(V)";
  e["mesh"]["iso"] = -60.0;  // log|q_1| never gets this low in the box: nothing is inside
  e["mesh"]["detail"] = 0.0;  // of the map as optimized (the smooth default would steepen it)
  Write(exp, e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  EXPECT_FALSE(fs::exists(out + "/mesh/julia.ply"));
  EXPECT_FALSE(fs::exists(out + "/pictures/render.png"));
  EXPECT_TRUE(fs::exists(out + "/pictures/slice-n1.png"));
  EXPECT_EQ(json::parse(Slurp(out + "/mesh/summary.json"))["triangles"], 0);
  EXPECT_NE(Slurp(out + "/report.md").find("No surface"), std::string::npos);
  fs::remove_all(dir);
}

// Passes that make no iteration (here: a tolerance no gradient is above) are flagged in the summary
// and the report, the plot draws what there is, and the run finishes with the start map.
TEST(RunTest, PassesThatCannotMoveAreReportedNotFatal) {
  const std::string dir = TempDir("stalled");
  const std::string exp = dir + "/tiny.json", out = dir + "/results";
  json e = Tiny();
  e["optimizer"]["schedule"] = json::parse(
      R"({"levels": [{"resolution": 10,
                      "passes": [{"kind": "V", "tolerance": 1e9}, {"kind": "F", "tolerance": 1e9}]}]})");
  e["optimizer"]["min_level_fidelity"] = 0;  // the level as written: the report names it
  e["mesh"]["enabled"] = false;
  Write(exp, e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  if (HaveGnuplot()) {
    EXPECT_TRUE(fs::exists(out + "/plot/convergence.png"));
  }
  const json s = json::parse(Slurp(out + "/optimized/summary.json"));
  ASSERT_EQ(s["passes"].size(), 2u);
  for (const json& p : s["passes"]) {
    EXPECT_EQ(p["iterations"], 0) << p;
    EXPECT_EQ(p["stalled"], true) << p;
    EXPECT_NE(p["stall_reason"].get<std::string>().find("tolerance"), std::string::npos) << p;
  }
  EXPECT_EQ(s["best_pass"], -1);
  EXPECT_EQ(s["absolute_end"], s["absolute_start"]);
  const std::string report = Slurp(out + "/report.md");
  EXPECT_NE(report.find("**Stalled:** level 10 pass V"), std::string::npos) << report;
  EXPECT_NE(report.find("**Stalled:** level 10 pass F"), std::string::npos) << report;
  const json start = json::parse(Slurp(out + "/initial/map.json"));
  const json result = json::parse(Slurp(out + "/optimized/map.json"));
  for (const char* k : {"top", "bottom", "ln_C", "tau", "beta"}) EXPECT_EQ(start[k], result[k]) << k;
  fs::remove_all(dir);
}

// No temporary file, no truncated JSON: what a failed run leaves is whole.
void ExpectNothingPartial(const std::string& out) {
  if (!fs::exists(out)) return;
  for (const auto& e : fs::recursive_directory_iterator(out)) {
    const std::string p = e.path().string();
    EXPECT_EQ(p.find(".tmp."), std::string::npos) << p;
    if (e.is_regular_file() && e.path().extension() == ".json") {
      EXPECT_TRUE(json::accept(Slurp(p))) << p;
    }
  }
}

// The results folder fills up mid-run: one clear line naming the file and the system's reason, no
// partial file; once there is room, --resume finishes the run. A real full disk (a 96 KiB tmpfs)
// when the test may mount one (root), else a file-size limit, which fails writes the same way.
TEST(RunTest, AFullDiskIsAClearErrorAndResumeFinishesTheRun) {
  const std::string dir = TempDir("full");
  const std::string exp = dir + "/tiny.json";
  Write(exp, Tiny().dump(1));
  const std::string disk = dir + "/disk", out = disk + "/results";
  fs::create_directories(disk);
  const bool tmpfs = ::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=96k") == 0;
  std::string err;
  EXPECT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err, nullptr, tmpfs ? 0 : 24 * 1024), 1) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find(tmpfs ? "No space left on device" : "File too large"), std::string::npos) << err;
  EXPECT_NE(err.find(disk), std::string::npos) << "the message names the file: " << err;
  ExpectNothingPartial(out);
  if (tmpfs) ::mount("tmpfs", disk.c_str(), "tmpfs", MS_REMOUNT, "size=64m");
  EXPECT_EQ(RunQ({"run", exp, "--out", out, "--resume", "--quiet"}, &err), 0) << err;
  EXPECT_TRUE(fs::exists(out + "/report.md"));
  EXPECT_TRUE(fs::exists(out + "/mesh/julia.ply"));
  ExpectNothingPartial(out);
  if (tmpfs) ::umount(disk.c_str());
  fs::remove_all(dir);
}

// Stopped as by a crash mid-optimization (QUIJIBO_TEST_EXIT_AFTER_STEP, optim/optimizer.cpp) and
// resumed with --resume, the run ends where an uninterrupted run ends: the same map and summary.
TEST(RunTest, KilledAndResumedRunMatchesAnUninterruptedOne) {
  const std::string dir = TempDir("kill");
  const json e = {{"seed", 5},
                  {"target", {{"analytic", "torus"}, {"resolution", 20}}},
                  {"initial", {{"kind", "random"}, {"top", 30}, {"bottom", 20}, {"root_radius", 1.5}}},
                  {"optimizer",
                   {{"schedule", "10(VF)20(VRF)"}, {"max_iterations", {{"F", 50}, {"R", 25}}}, {"checkpoint_every", 7},
                    {"min_level_fidelity", 0}}},
                  {"mesh", {{"enabled", false}}},
                  {"pictures", {{"enabled", false}}},
                  {"outputs", {{"plot", false}}}};
  const std::string exp = dir + "/kill.json";
  Write(exp, e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", dir + "/whole", "--quiet"}, &err), 0) << err;
  // Stop two thirds of the way (in the second level), between checkpoints.
  int steps = 0;
  {
    std::istringstream log(Slurp(dir + "/whole/optimized/log.jsonl"));
    for (std::string line; std::getline(log, line);)
      if (json::parse(line)["type"] == "iteration") steps = json::parse(line)["step"];
  }
  ASSERT_GT(steps, 20);
  const int stop = steps * 2 / 3;
  EXPECT_EQ(RunQ({"run", exp, "--out", dir + "/killed", "--quiet"}, &err, nullptr, 0,
                 "QUIJIBO_TEST_EXIT_AFTER_STEP=" + std::to_string(stop)),
            86)
      << err;
  EXPECT_FALSE(fs::exists(dir + "/killed/optimized/stage.json"));
  EXPECT_FALSE(fs::exists(dir + "/killed/optimized/map.json"));
  EXPECT_TRUE(fs::exists(dir + "/killed/optimized/checkpoint.json"));
  ASSERT_EQ(RunQ({"run", exp, "--out", dir + "/killed", "--resume", "--quiet"}, &err), 0) << err;
  EXPECT_EQ(Slurp(dir + "/whole/optimized/map.json"), Slurp(dir + "/killed/optimized/map.json"));
  auto without_clock = [](json s) {
    s.erase("seconds");
    for (json& p : s["passes"]) p.erase("seconds"), p.erase("band");  // band: work counters (output_compare.h)
    return s;
  };
  EXPECT_EQ(without_clock(json::parse(Slurp(dir + "/whole/optimized/summary.json"))),
            without_clock(json::parse(Slurp(dir + "/killed/optimized/summary.json"))));
  bool saw_resumed = false;
  for (const json& s : json(RunRecord(dir + "/killed")["stages"])) saw_resumed |= s["status"] == "resumed";
  EXPECT_TRUE(saw_resumed) << RunRecord(dir + "/killed").dump() << err;
  fs::remove_all(dir);
}

namespace interrupt {

// Every folder of a stage in `out` was made by the run recorded in run.json (or is the optimization
// that run left for --resume), and no "<stage>.partial" is left.
void ExpectOnlyThisRunsStages(const std::string& out) {
  const json run = RunRecord(out);
  std::vector<std::string> hashes;
  for (const json& s : run["stages"]) hashes.push_back(s["hash"]);
  for (const auto& e : fs::directory_iterator(out)) {
    const std::string p = e.path().string();
    EXPECT_EQ(p.find(".partial"), std::string::npos) << p;
    if (!fs::exists(p + "/stage.json")) continue;
    const std::string h = json::parse(Slurp(p + "/stage.json"))["hash"];
    EXPECT_NE(std::find(hashes.begin(), hashes.end(), h), hashes.end()) << p << " predates the run";
  }
}

// The one line of an interrupted run: the stage, the signal and the command that resumes it.
void ExpectInterruptLine(const std::string& err, const std::string& stage) {
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_EQ(err.rfind("quijibo: interrupted (SIGINT) in stage " + stage, 0), 0u) << err;
  EXPECT_NE(err.find("--resume"), std::string::npos) << err;
}

}  // namespace interrupt

// Ctrl-C in each stage of a run whose settings changed (QUIJIBO_TEST_SIGNAL_IN_STAGE sends the
// SIGINT as the stage starts computing): exit 130, one line, report.md and run.json INCOMPLETE
// naming the stage, and nothing of the earlier run's later stages left to pass for this run's.
TEST(RunTest, AnInterruptInEachStageLeavesAnIncompleteReportAndNoStaleOutputs) {
  const std::string dir = TempDir("interrupt");
  const std::string exp = dir + "/tiny.json", base = dir + "/base";
  Write(exp, Tiny().dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", base, "--quiet"}, &err), 0) << err;
  json changed = Tiny();
  changed["initial"]["root_radius"] = 1.1;  // every stage computes again
  Write(exp, changed.dump(1));
  std::vector<std::string> stages = {"initial", "optimized", "mesh", "intricate", "pictures", "fidelity", "triptych"};
  if (HaveGnuplot()) stages.insert(stages.begin() + 2, "plot");
  for (std::size_t k = 0; k < stages.size(); ++k) {
    const std::string& stage = stages[k];
    const std::string out = dir + "/" + stage;
    fs::copy(base, out, fs::copy_options::recursive);
    EXPECT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err, nullptr, 0, "QUIJIBO_TEST_SIGNAL_IN_STAGE=" + stage),
              130)
        << stage << ": " << err;
    interrupt::ExpectInterruptLine(err, stage == "optimized"   ? "optimize (optimized"
                                        : stage == "intricate" ? "mesh (intricate surface)"
                                                               : stage);
    const std::string report = Slurp(out + "/report.md");
    EXPECT_EQ(report.rfind("# tiny (INCOMPLETE)", 0), 0u) << stage << ": " << report;
    EXPECT_FALSE(fs::exists(out + "/report.html")) << stage;  // the finished run's page is gone
    EXPECT_NE(report.find("**INCOMPLETE:** the run stopped in stage"), std::string::npos) << report;
    EXPECT_NE(report.find("interrupted (SIGINT)"), std::string::npos) << report;
    EXPECT_NE(report.find("quijibo run " + exp + " --out " + out + " --resume"), std::string::npos) << report;
    const json run = RunRecord(out);
    EXPECT_EQ(run["complete"], false) << run;
    EXPECT_EQ(run["stopped"]["reason"], "interrupted (SIGINT)") << run;
    EXPECT_EQ(run["stages"].size(), k) << run;  // the stages before it finished
    for (std::size_t later = k; later < stages.size(); ++later)
      EXPECT_FALSE(fs::exists(out + "/" + stages[later] + "/stage.json")) << stage << ": " << stages[later];
    interrupt::ExpectOnlyThisRunsStages(out);
  }
  // Resumed, the run finishes and the report is whole again.
  ASSERT_EQ(RunQ({"run", exp, "--out", dir + "/mesh", "--resume", "--quiet"}, &err), 0) << err;
  EXPECT_EQ(Slurp(dir + "/mesh/report.md").find("INCOMPLETE"), std::string::npos);
  EXPECT_EQ(RunRecord(dir + "/mesh")["complete"], true);
  EXPECT_TRUE(fs::exists(dir + "/mesh/pictures/render.png"));
  EXPECT_TRUE(fs::exists(dir + "/mesh/report.html"));
  // Interrupted before any stage finished, a results folder the run created goes again.
  EXPECT_EQ(RunQ({"run", exp, "--out", dir + "/fresh", "--quiet"}, &err, nullptr, 0,
                 "QUIJIBO_TEST_SIGNAL_IN_STAGE=initial"),
            130)
      << err;
  EXPECT_FALSE(fs::exists(dir + "/fresh")) << err;
  fs::remove_all(dir);
}

// The same for the stages of the other methods: modulus (and its render), portal.
TEST(RunTest, AnInterruptInTheModulusOrPortalStageLeavesAnIncompleteReport) {
  const std::string dir = TempDir("interrupt_products");
  const json modulus = {{"name", "m"},
                        {"method", "modulus"},
                        {"target", {{"analytic", "sphere"}}},
                        {"modulus", {{"sdf_resolution", 16}, {"output", {{"format", "ply"}, {"resolution", 16}}}}},
                        {"pictures", {{"render_size", 32}, {"render_views", 1}}}};
  const json portal = {{"name", "p"},
                       {"method", "portal"},
                       {"portal", {{"koch", true}, {"output", {{"format", "png"}, {"png_size", 32}}}}}};
  struct Case {
    json experiment;
    std::string stage;
  };
  for (const Case& c : {Case{modulus, "modulus"}, Case{modulus, "pictures"}, Case{portal, "portal"}}) {
    const std::string exp = dir + "/" + c.stage + ".json", out = dir + "/" + c.stage;
    Write(exp, c.experiment.dump(1));
    std::string err;
    ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
    json changed = c.experiment;
    changed["name"] = "changed";  // not hashed: the output settings are
    if (c.stage == "portal") changed["portal"]["output"]["png_size"] = 40;
    else changed["modulus"]["output"]["resolution"] = 18;
    Write(exp, changed.dump(1));
    EXPECT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err, nullptr, 0, "QUIJIBO_TEST_SIGNAL_IN_STAGE=" + c.stage),
              130)
        << c.stage << ": " << err;
    interrupt::ExpectInterruptLine(err, c.stage);
    EXPECT_EQ(Slurp(out + "/report.md").rfind("# changed (INCOMPLETE)", 0), 0u) << Slurp(out + "/report.md");
    EXPECT_FALSE(fs::exists(out + "/pictures")) << c.stage;
    interrupt::ExpectOnlyThisRunsStages(out);
  }
  fs::remove_all(dir);
}

// A stage that fails (here the initial stage, given a map in another frame than the target's)
// leaves the report INCOMPLETE with the error as the reason, and none of the earlier run's later
// stages; the command says the one line of the error.
TEST(RunTest, AFailedStageLeavesAnIncompleteReportWithTheReason) {
  const std::string dir = TempDir("failed");
  const std::string exp = dir + "/tiny.json", out = dir + "/results";
  Write(exp, Tiny().dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  json map = json::parse(Slurp(out + "/optimized/map.json"));
  map["frame"]["origin"] = {0.4, 0.5, 0.5};
  Write(dir + "/moved.json", map.dump());
  json changed = Tiny();
  changed["initial"] = {{"kind", "map"}, {"map", "moved.json"}};
  Write(exp, changed.dump(1));
  EXPECT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 1) << err;
  EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
  EXPECT_NE(err.find("is not the map's (" + dir + "/moved.json): origin (0.5, 0.5, 0.5) vs (0.4, 0.5, 0.5)"),
            std::string::npos)
      << err;
  const std::string report = Slurp(out + "/report.md");
  EXPECT_NE(report.find("**INCOMPLETE:** the run stopped in stage initial: "), std::string::npos) << report;
  EXPECT_NE(report.find("is not the map's"), std::string::npos) << report;
  for (const char* gone : {"initial", "optimized", "mesh", "pictures", "fidelity", "plot"})
    EXPECT_FALSE(fs::exists(out + "/" + std::string(gone))) << gone;
  EXPECT_EQ(RunRecord(out)["complete"], false);
  fs::remove_all(dir);
}

// Ctrl-C inside the optimization (QUIJIBO_TEST_SIGNAL_AFTER_STEP): the optimizer writes its
// checkpoint, the run exits 130 with one line, the report names no map that is not there, and
// --resume continues from the checkpoint.
TEST(RunTest, AnInterruptedOptimizationKeepsItsCheckpointAndSaysSo) {
  const std::string dir = TempDir("interrupt_opt");
  const std::string exp = dir + "/tiny.json", out = dir + "/results";
  Write(exp, Tiny().dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  json changed = Tiny();
  changed["optimizer"]["max_iterations"]["F"] = 14;  // the optimization and what follows compute again
  Write(exp, changed.dump(1));
  EXPECT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err, nullptr, 0, "QUIJIBO_TEST_SIGNAL_AFTER_STEP=3"), 130)
      << err;
  const std::string line = err.substr(err.rfind("quijibo: "));  // after the optimizer's table
  interrupt::ExpectInterruptLine(line, "optimize (optimized");
  EXPECT_TRUE(fs::exists(out + "/optimized/checkpoint.json"));
  EXPECT_FALSE(fs::exists(out + "/optimized/map.json"));
  for (const char* gone : {"mesh", "pictures", "plot"}) EXPECT_FALSE(fs::exists(out + "/" + gone)) << gone;
  const std::string report = Slurp(out + "/report.md");
  EXPECT_EQ(report.rfind("# tiny (INCOMPLETE)", 0), 0u) << report;
  EXPECT_EQ(report.find("optimized/map.json"), std::string::npos) << report;
  EXPECT_NE(report.find("optimized/checkpoint.json"), std::string::npos) << report;
  interrupt::ExpectOnlyThisRunsStages(out);
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--resume", "--quiet"}, &err), 0) << err;
  bool resumed = false;
  for (const json& s : json(RunRecord(out)["stages"])) resumed |= s["status"] == "resumed";
  EXPECT_TRUE(resumed) << RunRecord(out).dump();
  EXPECT_EQ(Slurp(out + "/report.md").find("INCOMPLETE"), std::string::npos);
  fs::remove_all(dir);
}

namespace quality {

// An experiment that keeps the initial map (`map` file) as the result: passes that cannot move
// (tolerance 1e9, as in PassesThatCannotMoveAreReportedNotFatal) on an analytic target.
json Kept(const std::string& target, const std::string& map, int n) {
  return {{"name", "kept"},
          {"target", {{"analytic", target}, {"resolution", 16}}},
          {"initial", {{"kind", "map"}, {"map", map}}},
          {"optimizer",
           {{"schedule", json::parse(R"({"levels": [{"resolution": 10, "passes": [{"kind": "V", "tolerance": 1e9}]}]})")},
            {"min_level_fidelity", 0}}},
          {"mesh", {{"resolution", 16}, {"iterations", n}}},
          {"pictures", {{"enabled", false}}},
          {"outputs", {{"plot", false}}}};
}

// A map of one root at the origin: R(q) = C q^{+-1}.
std::string OneRootMap(bool top, double ln_C) {
  const json root = json::array({json{{"root", {0.0, 0.0, 0.0, 0.0}}, {"exponent", 1.0}}});
  return json{{"format", "quijibo-map"}, {"version", 1}, {"ln_C", ln_C}, {"tau", 1.0}, {"beta", 1.0},
              {"top", top ? root : json::array()}, {"bottom", top ? json::array() : root}}
      .dump(1);
}

// The warnings of run.json, all in one string, and checks that report.md states each of them.
std::string Warnings(const std::string& out) {
  const json run = RunRecord(out);
  std::string all;
  const std::string report = Slurp(out + "/report.md");
  EXPECT_NE(report.find("## Quality"), std::string::npos) << report;
  for (const json& w : run["quality"]["warnings"]) {
    all += w.get<std::string>() + "\n";
    EXPECT_NE(report.find("**Warning:** " + w.get<std::string>()), std::string::npos) << w;
  }
  return all;
}

}  // namespace quality

// The exact one-step sphere (R = q, the unit ball) meshed at n = 1: the figures are in report.md
// and run.json, and no threshold fires on a good result.
TEST(RunTest, AGoodResultIsReportedWithItsFiguresAndNoWarning) {
  const std::string dir = TempDir("quality_good");
  Write(dir + "/map.json", quality::OneRootMap(true, 0.0));
  Write(dir + "/e.json", quality::Kept("sphere", "map.json", 1).dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", dir + "/e.json", "--out", dir + "/r", "--quiet"}, &err), 0) << err;
  const json q = RunRecord(dir + "/r")["quality"];
  EXPECT_GT(q["figures"]["one_step"]["iou"].get<double>(), 0.9) << q;
  EXPECT_EQ(q["figures"]["one_step"]["leak"], 0.0) << q;
  EXPECT_EQ(q["figures"]["n_step"]["n"], 1) << q;
  EXPECT_EQ(q["figures"]["mesh"]["components"], 1) << q;
  EXPECT_EQ(q["figures"]["mesh"]["open_edges_inside"], 0) << q;
  EXPECT_EQ(q["figures"]["start"]["inverted"], false) << q;
  EXPECT_EQ(quality::Warnings(dir + "/r"), "");
  EXPECT_NE(Slurp(dir + "/r/report.md").find("No warning."), std::string::npos);
  fs::remove_all(dir);
}

// R = C / q with ln C = -50 on the torus: |R| < 1 almost everywhere, so the one-step set and the
// n = 3 set (q_2 = q, q_3 = C / q) fill the box and leak far beyond the shape box, L falls outward
// (inverted) and tanh is flat everywhere (saturated); the torus's centre, the fractal origin, is
// outside it: each of these is a warning, in run.json and report.md.
TEST(RunTest, ASetThatFillsTheBoxFromAnInvertedSaturatedStartIsWarnedAbout) {
  const std::string dir = TempDir("quality_bad");
  Write(dir + "/map.json", quality::OneRootMap(false, -50.0));
  Write(dir + "/e.json", quality::Kept("torus", "map.json", 3).dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", dir + "/e.json", "--out", dir + "/r", "--quiet"}, &err), 0) << err;
  const std::string w = quality::Warnings(dir + "/r");
  // ... and on stderr at the end of the run, with --quiet too.
  std::string printed, line;
  for (std::istringstream lines(err); std::getline(lines, line);)
    if (line.rfind("quijibo: quality warning: ", 0) == 0) printed += line + "\n";
  for (const char* expect : {"the one-step set leaks", "the n = 3 set fills the box", "the n = 3 set leaks",
                             "the start is inverted", "the start is saturated",
                             "one-step set does not follow the shape", "origin lies outside the shape"}) {
    EXPECT_NE(w.find(expect), std::string::npos) << expect << " in\n" << w;
    EXPECT_NE(printed.find(expect), std::string::npos) << expect << " in\n" << err;
  }
  fs::remove_all(dir);
}

// The shape modulus of a torus (64 triangles): the iteration's origin, the box centre, lies in the
// hole, outside the shape; the run warns on stderr, in run.json and in report.md.
TEST(RunTest, AShapeModulusWhoseOriginIsOutsideTheShapeIsWarnedAbout) {
  const std::string dir = TempDir("quality_modulus");
  std::ostringstream obj;
  const int u = 8, v = 4;  // 8 x 4 quads, 64 triangles
  const double pi = 3.14159265358979323846;
  for (int i = 0; i < u; ++i)
    for (int j = 0; j < v; ++j) {
      const double a = 2 * pi * i / u, b = 2 * pi * j / v, r = 1.0 + 0.35 * std::cos(b);
      obj << "v " << r * std::cos(a) << " " << r * std::sin(a) << " " << 0.35 * std::sin(b) << "\n";
    }
  auto id = [&](int i, int j) { return (i % u) * v + (j % v) + 1; };
  for (int i = 0; i < u; ++i)
    for (int j = 0; j < v; ++j) {
      obj << "f " << id(i, j) << " " << id(i + 1, j) << " " << id(i + 1, j + 1) << "\n";
      obj << "f " << id(i, j) << " " << id(i + 1, j + 1) << " " << id(i, j + 1) << "\n";
    }
  Write(dir + "/torus.obj", obj.str());
  const json e = {{"name", "torus-modulus"},
                  {"method", "modulus"},
                  {"target", {{"mesh", "torus.obj"}}},
                  {"modulus", {{"sdf_resolution", 24}, {"output", {{"format", "ply"}, {"resolution", 24}, {"iterations", 2}}}}},
                  {"pictures", {{"enabled", false}}}};
  Write(dir + "/e.json", e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", dir + "/e.json", "--out", dir + "/r", "--quiet"}, &err), 0) << err;
  EXPECT_NE(err.find("quijibo: warning: the iteration's origin lies outside the shape"), std::string::npos) << err;
  const json q = RunRecord(dir + "/r")["quality"];
  EXPECT_EQ(q["figures"]["origin"]["inside"], false) << q;
  EXPECT_NE(quality::Warnings(dir + "/r").find("origin lies outside the shape"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
