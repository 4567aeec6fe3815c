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
          {"pictures", {{"slice_size", 48}, {"render_size", 48}, {"render_views", 2}}},
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
                        "mesh/summary.json", "pictures/slice-n1.png", "pictures/render.png"})
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
    EXPECT_EQ(s["status"], name == "mesh" || name == "pictures" ? "ran" : "reused") << s;
  }
  EXPECT_EQ(json::parse(Slurp(out + "/mesh/summary.json"))["resolution"], 22);
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
      {"outputs", {{"plot", false}}}};
  Write(exp, e.dump(1));
  std::string err;
  ASSERT_EQ(RunQ({"run", exp, "--out", out, "--quiet"}, &err), 0) << err;
  for (const char* f : {"initial/roots.ply", "initial/potential.png", "initial/monopoles.json", "optimized/map.json",
                        "pictures/slice-n1.png", "report.md"})
    EXPECT_TRUE(fs::exists(out + "/" + f)) << f;
  EXPECT_NE(Slurp(out + "/report.md").find("Initial guess"), std::string::npos);
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

}  // namespace
