// Kill and resume without timing: QUIJIBO_TEST_EXIT_AFTER_STEP=k makes `quijibo optimize` end as a
// crash would right after step k (optim/optimizer.cpp). The run is resumed and every file it leaves
// is compared with an uninterrupted run's, byte for byte (logs, summary and checkpoint without their
// wall-clock fields), for both back ends and for stops on and between checkpoints.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "output_compare.h"
#include "optim/optimizer.h"
#include "quijibo_command.h"

namespace quijibo::optim {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::ExpectSameOutputs;
using testing::RunQuijibo;
using testing::SlurpFile;


std::vector<std::string> LogLines(const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(testing::Comparable(path));
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

struct Stop {
  int step;
  bool at_checkpoint;
};

class KillResume : public ::testing::TestWithParam<std::string> {};

// Stops after chosen steps of an uninterrupted run's log (on a checkpoint, between checkpoints, in
// the R pass), resumes each, and compares.
TEST_P(KillResume, ResumedRunsMatchAnUninterruptedOneByteForByte) {
  const std::string backend = GetParam();
  const std::string dir = (fs::temp_directory_path() / ("quijibo_resume_" + backend)).string();
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string map = dir + "/init.json";
  ASSERT_EQ(RunQuijibo("map random --top 40 --bottom 30 --seed 5 --center-on torus --target-resolution 24 -o " + map)
                .code,
            0);
  const std::string common = "optimize -t torus --target-resolution 24 -m " + map +
                             " -s '12(VF)24(VRF)' --min-level-fidelity 0 --max-v 40 --max-f 60 --max-r 30 --checkpoint-every 7"
                             " --weights layer"
                             " --backend " + backend;
  const auto whole = RunQuijibo(common + " -o " + dir + "/whole");
  ASSERT_EQ(whole.code, 0) << whole.out;

  // The stops, from the uninterrupted log.
  std::vector<Stop> stops;
  bool on = false, between = false, in_r = false;
  int steps = 0;
  for (const std::string& line : LogLines(dir + "/whole/log.jsonl")) {
    const json j = json::parse(line);
    if (j["type"] != "iteration") continue;
    const int step = j["step"], it = j["iteration"];
    steps = step;
    if (j["level_index"] == 0 && j["pass"] == "F" && it % 7 == 0 && !on) stops.push_back({step, true}), on = true;
    if (j["level_index"] == 1 && it % 7 == 3 && !between) stops.push_back({step, false}), between = true;
    if (j["pass"] == "R" && it % 7 == 5 && !in_r) stops.push_back({step, false}), in_r = true;
  }
  ASSERT_EQ(stops.size(), 3u) << "the uninterrupted run is too short for the stops this test needs (" << steps
                              << " steps)";
  for (const Stop& stop : stops) {
    SCOPED_TRACE("exit after step " + std::to_string(stop.step));
    const std::string out = dir + "/killed-" + std::to_string(stop.step);
    const auto killed = RunQuijibo(common + " -o " + out, "QUIJIBO_TEST_EXIT_AFTER_STEP=" + std::to_string(stop.step));
    ASSERT_EQ(killed.code, kTestExitCode) << killed.out;
    EXPECT_FALSE(fs::exists(out + "/map.json"));
    EXPECT_FALSE(fs::exists(out + "/summary.json"));
    const json c = json::parse(SlurpFile(out + "/checkpoint.json"));
    EXPECT_FALSE(c["complete"].get<bool>());
    // The log ends with the step it stopped after.
    const std::vector<std::string> lines = LogLines(out + "/log.jsonl");
    int last_step = 0;
    for (const std::string& l : lines)
      if (json::parse(l)["type"] == "iteration") last_step = json::parse(l)["step"];
    EXPECT_EQ(last_step, stop.step);
    // On a checkpoint the checkpoint is that step's; between, an earlier one the resume goes back to.
    if (stop.at_checkpoint) {
      EXPECT_EQ(c["step"], stop.step);
    } else {
      EXPECT_LT(c["step"].get<int>(), stop.step);
    }
    const auto resumed = RunQuijibo(common + " -o " + out + " --resume");
    ASSERT_EQ(resumed.code, 0) << resumed.out;
    ExpectSameOutputs(dir + "/whole", out);
  }
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Backends, KillResume, ::testing::Values("lbfgspp", "ceres"));

}  // namespace
}  // namespace quijibo::optim
