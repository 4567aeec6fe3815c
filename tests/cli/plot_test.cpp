// `quijibo plot` as a user meets it: PNG and SVG from optimizer logs, one-line errors, and no
// output files after a failure. Skipped when gnuplot is not installed.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "quijibo_command.h"

namespace quijibo {
namespace {

using testing::CommandResult;
using testing::RunQuijibo;
CommandResult Shell(const std::string& cmd) { return testing::RunShell(cmd); }

bool HaveGnuplot() { return Shell("gnuplot --version").code == 0; }

std::string Slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A synthetic run: passes (level, pass) of `steps` iterations each, the relative energy falling
// within a pass and jumping at level changes, absolute energies every 5 steps and at pass ends.
std::string SyntheticLog(const std::string& label, double offset) {
  struct Pass {
    int level;
    const char* name;
  };
  const Pass passes[] = {{25, "V"}, {25, "F"}, {50, "F"}, {97, "R"}};
  std::ostringstream s;
  s << R"({"type":"run","backend":"loglinear","precision":"double","schedule":"paper","label":")" << label
    << R"(","extra_key":[1,2]})" << "\n";
  int step = 0;
  for (int p = 0; p < 4; ++p) {
    const int level_index = passes[p].level == 25 ? 0 : passes[p].level == 50 ? 1 : 2;
    const std::string where = R"("level":)" + std::to_string(passes[p].level) + R"(,"level_index":)" +
                              std::to_string(level_index) + R"(,"pass":")" + passes[p].name +
                              R"(","pass_index":)" + std::to_string(p);
    s << R"({"type":"pass_start","step":)" << step << "," << where << R"(,"seconds":1.0})" << "\n";
    double psi = 0;
    for (int i = 1; i <= 20; ++i) {
      ++step;
      psi = -1 + offset + 0.8 * std::exp(-0.05 * step) + 0.05 * std::exp(-0.3 * i);
      s << R"({"type":"iteration","step":)" << step << "," << where << R"(,"iteration":)" << i
        << R"(,"evaluations":)" << i + 1 << R"(,"energy":)" << psi << R"(,"projected_gradient":1e-3,"seconds":2})"
        << "\n";
      if (step % 5 == 0)
        s << R"({"type":"absolute","step":)" << step << "," << where << R"(,"iteration":)" << i
          << R"(,"energy":)" << psi + 0.02 << R"(,"seconds":2})" << "\n";
    }
    s << R"({"type":"pass_end","step":)" << step << "," << where
      << R"(,"iterations":20,"evaluations":25,"stop":"tolerance","energy":)" << psi
      << R"(,"absolute_energy":)" << psi + 0.015 << R"(,"seconds":3})" << "\n";
  }
  return s.str();
}

class PlotTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!HaveGnuplot()) GTEST_SKIP() << "gnuplot is not installed (apt-get install gnuplot-nox)";
    dir_ = std::filesystem::temp_directory_path() /
           ("quijibo_plot_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  void Write(const std::string& name, const std::string& text) const {
    std::filesystem::create_directories((dir_ / name).parent_path());
    std::ofstream(Path(name)) << text;
  }
  // Files in the test folder other than the logs (outputs and any leftover temporaries).
  std::vector<std::string> Outputs() const {
    std::vector<std::string> found;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir_))
      if (e.is_regular_file() && e.path().extension() != ".jsonl" && e.path().extension() != ".json")
        found.push_back(e.path().string());
    return found;
  }
  std::filesystem::path dir_;
};

TEST_F(PlotTest, TwoLogsGiveAPngAndAnSvgWithLabelledAxes) {
  // One log ends in a line cut short by a killed run; its label comes from its folder.
  std::string a = SyntheticLog("", 0.02);
  a += R"({"type":"iteration","step":81,"level":97,"level_in)";
  Write("bunny/log.jsonl", a);
  Write("float.jsonl", SyntheticLog("cached float", 0.05));
  const std::string prefix = Path("convergence");
  const CommandResult r =
      RunQuijibo("plot " + Path("bunny/log.jsonl") + " " + Path("float.jsonl") + " -o " + prefix +
              " --title 'Bunny: it'\\''s \"50%\" @done `x`' --width 900 --height 600");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("log.jsonl:"), std::string::npos) << "warning about the truncated line: " << r.out;

  const std::string png = Slurp(prefix + ".png");
  ASSERT_GT(png.size(), 5000u);
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const std::string svg = Slurp(prefix + ".svg");
  ASSERT_GT(svg.size(), 1000u);
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  for (const char* text : {"optimization step", "(psi + 1) / 2", "bunny relative", "bunny absolute",
                           "cached float relative", "cached float absolute", "25 V", "50 F", "97 R"})
    EXPECT_NE(svg.find(text), std::string::npos) << text;
  // Only the two outputs: no temporary files left behind.
  std::vector<std::string> outputs = Outputs();
  std::sort(outputs.begin(), outputs.end());
  EXPECT_EQ(outputs, (std::vector<std::string>{prefix + ".png", prefix + ".svg"}));

  // --label overrides; a second run replaces the outputs.
  const CommandResult l = RunQuijibo("plot " + Path("float.jsonl") + " -o " + prefix + " --label \"it's mine\"");
  ASSERT_EQ(l.code, 0) << l.out;
  EXPECT_NE(Slurp(prefix + ".svg").find("mine relative"), std::string::npos);
}

TEST_F(PlotTest, BadInputGetsOneLineAndNoOutputFiles) {
  auto expect_error = [&](const std::string& args, const std::string& needle) {
    const CommandResult r = RunQuijibo(args);
    EXPECT_NE(r.code, 0) << args;
    EXPECT_NE(r.out.find(needle), std::string::npos) << args << "\n got: " << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_TRUE(Outputs().empty()) << args;
  };
  const std::string prefix = Path("out");
  expect_error("plot " + Path("missing.jsonl") + " -o " + prefix, "missing.jsonl");
  // A garbage line in the middle is an error naming file:line (line 1 is the run header).
  std::string log = SyntheticLog("x", 0.02);
  const auto third = log.find('\n', log.find('\n', log.find('\n') + 1) + 1);
  log.insert(third + 1, "{\"type\":\"iteration\", garbage\n");
  Write("garbage.jsonl", log);
  expect_error("plot " + Path("garbage.jsonl") + " -o " + prefix, "garbage.jsonl:4:");
  // A well-formed line with a bad value.
  Write("bad_step.jsonl", SyntheticLog("x", 0.02) + R"({"type":"iteration","step":"ten","energy":0})" + "\n" +
                              R"({"type":"iteration","step":11,"energy":0})" + "\n");
  expect_error("plot " + Path("bad_step.jsonl") + " -o " + prefix, "bad_step.jsonl:");
  // No energies at all.
  Write("empty.jsonl", R"({"type":"run","backend":"cached"})" "\n");
  expect_error("plot " + Path("empty.jsonl") + " -o " + prefix, "no energies");
  // A pretty-printed JSON file (summary.json) is not a log, and is called so.
  Write("summary.json", "{\n  \"frame\": \"user\"\n}\n");
  expect_error("plot " + Path("summary.json") + " -o " + prefix, "summary.json: not a log.jsonl (expected an optimizer log");
  Write("one_line.json", R"({"format":"quijibo-map"})" "\n");
  expect_error("plot " + Path("one_line.json") + " -o " + prefix, "one_line.json: not a log.jsonl");
  // An output folder that cannot be created; one that does not exist yet is created.
  Write("ok.jsonl", SyntheticLog("x", 0.02));
  expect_error("plot " + Path("ok.jsonl") + " -o " + Path("ok.jsonl/out"), "cannot create folder");
  // More labels than logs.
  expect_error("plot " + Path("ok.jsonl") + " -o " + prefix + " --label a --label b", "--label");
}

// What the optimizer writes when no pass made an iteration: the run line with the start's absolute
// energy and pass start/end lines with "absolute_end", all at step 0. The plot draws that point.
TEST_F(PlotTest, ALogWithoutIterationsStillGivesAPlot) {
  std::ostringstream log;
  log << R"j({"type":"run","schedule":"10(VF)","step":0,"absolute_energy":-0.125,"seconds":0.1})j" << "\n";
  for (int p = 0; p < 2; ++p) {
    const std::string where = R"("level":10,"level_index":0,"pass":")" + std::string(p ? "F" : "V") +
                              R"(","pass_index":)" + std::to_string(p);
    log << R"({"type":"pass_start","step":0,)" << where << R"(,"seconds":0.2})" << "\n";
    log << R"({"type":"pass_end","step":0,)" << where
        << R"(,"stop":"tolerance","iterations":0,"evaluations":1,"absolute_end":-0.125,"stalled":true})" << "\n";
  }
  Write("stalled/log.jsonl", log.str());
  const std::string prefix = Path("convergence");
  const CommandResult r = RunQuijibo("plot " + Path("stalled/log.jsonl") + " -o " + prefix);
  ASSERT_EQ(r.code, 0) << r.out;
  const std::string svg = Slurp(prefix + ".svg");
  EXPECT_NE(svg.find("stalled absolute"), std::string::npos);
  EXPECT_NE(svg.find("no iterations"), std::string::npos);
  EXPECT_GT(Slurp(prefix + ".png").size(), 1000u);
}

TEST_F(PlotTest, MissingGnuplotIsAClearError) {
  Write("ok.jsonl", SyntheticLog("x", 0.02));
  const CommandResult r =
      Shell("PATH=/nonexistent " + std::string(QUIJIBO_BINARY) + " --quiet plot " + Path("ok.jsonl") + " -o " +
          Path("out"));
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.out.find("gnuplot-nox"), std::string::npos) << r.out;
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  EXPECT_TRUE(Outputs().empty());
}

}  // namespace
}  // namespace quijibo
