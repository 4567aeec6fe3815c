// `quijibo optimize` as a user runs it: its settings are OptimizeOptions', caps go with the notation
// only, and --resume after a change of settings is refused with the setting named.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "optim/optimizer.h"
#include "quijibo_command.h"

namespace quijibo::optim {
namespace {

namespace fs = std::filesystem;
using testing::RunQuijibo;


class OptimizeCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    // A folder of this test's own (ctest runs test cases in parallel).
    dir_ = (fs::temp_directory_path() /
            ("quijibo_optimize_command_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())))
               .string();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    map_ = dir_ + "/init.json";
    ASSERT_EQ(RunQuijibo("map random --top 12 --bottom 9 --seed 5 --center-on torus --target-resolution 16 -o " + map_)
                  .code,
              0);
    std::ofstream(dir_ + "/s.json") << R"({"levels": [{"resolution": 8, "passes": [{"kind": "V", "max_iterations": 4},
                                           {"kind": "F", "max_iterations": 6}]}]})";
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Common() const { return "optimize -t torus --target-resolution 16 -m " + map_ + " -o " + dir_ + "/out"; }
  std::string dir_, map_;
};

TEST_F(OptimizeCommand, CapsAndToleranceGoWithTheNotationOnly) {
  for (const char* option : {"--max-v 3", "--max-f 3", "--max-r 3", "--tolerance 1e-3"}) {
    const auto r = RunQuijibo(Common() + " -s " + dir_ + "/s.json " + option);
    EXPECT_EQ(r.code, 1) << option;
    EXPECT_NE(r.out.find(std::string(option).substr(0, std::string(option).find(' ')) +
                         " does not apply to the JSON schedule"),
              std::string::npos)
        << r.out;
    EXPECT_NE(r.out.find("put the caps and tolerances in the file"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir_ + "/out/log.jsonl"));
  }
  EXPECT_EQ(RunQuijibo(Common() + " -s " + dir_ + "/s.json").code, 0);
  EXPECT_EQ(RunQuijibo(Common() + " -s '8(VF)' --max-v 3 --max-f 4 --tolerance 1e-3").code, 0);
}

// The README's mistake: resuming without the -s the run was started with.
TEST_F(OptimizeCommand, ResumeWithOtherSettingsIsRefusedNamingTheSetting) {
  const std::string started = Common() + " -s " + dir_ + "/s.json --checkpoint-every 2";
  const auto killed = RunQuijibo(started, "QUIJIBO_TEST_EXIT_AFTER_STEP=6");
  ASSERT_EQ(killed.code, kTestExitCode) << killed.out;
  const std::string resume = "optimize -t torus -o " + dir_ + "/out --resume --checkpoint-every 2 --target-resolution ";
  auto r = RunQuijibo(resume + "16");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("quijibo: error: --resume: the checkpoint was written with optimizer.schedule.notation = "
                       "\"8(VF)\", this run has \"25(VFRF)50(VFRF)97(VF)\"; rerun without --resume or with the same "
                       "settings"),
            std::string::npos)
      << r.out;
  r = RunQuijibo(resume + "16 -s " + dir_ + "/s.json --alpha 9");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("optimizer.alpha = 10.0, this run has 9.0"), std::string::npos) << r.out;
  r = RunQuijibo(resume + "17 -s " + dir_ + "/s.json");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.out.find("--resume: the target differs"), std::string::npos) << r.out;
  // The same settings continue.
  r = RunQuijibo(resume + "16 -s " + dir_ + "/s.json");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists(dir_ + "/out/map.json"));
}

}  // namespace
}  // namespace quijibo::optim
