// `quijibo film`: the frames and the video, a rerun that redoes only the missing frames, settings
// that changed (the frames start again), bad input (one line, no output).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "quijibo_command.h"

namespace quijibo {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using quijibo::testing::CommandResult;
using quijibo::testing::RunQuijibo;

class FilmCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("quijibo_film_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_EQ(RunQuijibo("map random --top 6 --bottom 4 --seed 3 --center-on sphere --target-resolution 12 -o " +
                         Path("map.json"))
                  .code,
              0);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  bool Exists(const std::string& name) const { return fs::exists(Path(name)); }
  static json Parse(const std::string& out) { return json::parse(out.substr(out.find('{'))); }
  fs::path dir_;
};

const char* kSmall = " -r 16 --size 48 --samples 1 --ao-rays 2";
bool HaveFfmpeg() { return std::system("ffmpeg -version > /dev/null 2>&1") == 0; }

TEST_F(FilmCli, FramesVideoAndAResumeThatRedoesOnlyMissingFrames) {
  const std::string cmd = "film --map " + Path("map.json") + " --vary translation --from 0 --to 0.4 --frames 4 -n 3" +
                          kSmall + " -o " + Path("film");
  CommandResult r = RunQuijibo(cmd);
  ASSERT_EQ(r.code, 0) << r.out;
  json s = Parse(r.out);
  EXPECT_EQ(s["frames"], 4);
  EXPECT_EQ(s["made"], 4);
  EXPECT_EQ(s["reused"], 0);
  for (const char* f : {"film/frames/frame-0001.png", "film/frames/frame-0004.png", "film/frames/frame-0004.json",
                        "film/frames.json", "film/film.json", "film/summary.json"})
    EXPECT_TRUE(Exists(f)) << f;
  if (HaveFfmpeg()) {
    EXPECT_TRUE(Exists("film/film.mp4")) << s["video_note"];
  }
  // The setting moves: the translation's length goes from 0 to 0.4 along z.
  const json frames = json::parse(std::ifstream(Path("film/frames.json")));
  ASSERT_EQ(frames.size(), 4u);
  EXPECT_EQ(frames[0]["translation"][2], 0.0);
  EXPECT_NEAR(frames[3]["translation"][2].get<double>(), 0.4, 1e-12);
  // An interrupted film (its last frames missing): the rerun makes only those.
  fs::remove(Path("film/frames/frame-0003.png"));
  fs::remove(Path("film/frames/frame-0004.json"));
  r = RunQuijibo(cmd);
  ASSERT_EQ(r.code, 0) << r.out;
  s = Parse(r.out);
  EXPECT_EQ(s["made"], 2);
  EXPECT_EQ(s["reused"], 2);
  // Other settings: the earlier frames are not this film's and go.
  r = RunQuijibo("film --map " + Path("map.json") + " --vary translation --from 0 --to 0.3 --frames 3 -n 3" + kSmall +
                 " --no-video -o " + Path("film"));
  ASSERT_EQ(r.code, 0) << r.out;
  s = Parse(r.out);
  EXPECT_EQ(s["made"], 3);
  EXPECT_FALSE(Exists("film/frames/frame-0004.png"));
  EXPECT_FALSE(Exists("film/film.mp4"));
}

TEST_F(FilmCli, AFilmFileMovesAnExponentAndIterations) {
  std::ofstream(Path("exponent.json")) << json({{"map", "map.json"},
                                                {"vary", "exponent"},
                                                {"root", 2},
                                                {"to", 3.0},
                                                {"frames", 2},
                                                {"video", false},
                                                {"mesh", {{"resolution", 16}, {"detail", 0.25}}},
                                                {"render", {{"size", 32}, {"samples", 1}, {"ao_rays", 0}}}})
                                              .dump();
  CommandResult r = RunQuijibo("film " + Path("exponent.json"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_TRUE(fs::exists("results/exponent/frames/frame-0002.png"));
  const json frames = json::parse(std::ifstream("results/exponent/frames.json"));
  EXPECT_EQ(frames[1]["value"], 3.0);
  fs::remove_all("results/exponent");
  r = RunQuijibo("film --map " + Path("map.json") + " --vary iterations --from 1 --to 3 --frames 3 --no-video" +
                 kSmall + " -o " + Path("n"));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(Parse(r.out)["made"], 3);
}

TEST_F(FilmCli, BadInputIsOneLineAndWritesNothing) {
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {"--map " + Path("map.json") + " --vary root --frames 3 -o " + Path("bad"), "to_position"},
      {"--map " + Path("map.json") + " --vary translate_potential --to 1 -o " + Path("bad"), "must be < 0"},
      {"--map " + Path("map.json") + " --vary exponent --root 99 --to 2 -o " + Path("bad"), "root 99"},
      {"--vary detail --to 2 -o " + Path("bad"), "give the map"},
      {"--map " + Path("map.json") + " --vary detail --to 2", "--out is required"},
      {Path("map.json") + " --frames 3", "not both"},
  };
  for (const Case& c : cases) {
    const CommandResult r = RunQuijibo("film " + c.args);
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_NE(r.out.find(c.expect), std::string::npos) << c.args << ": " << r.out;
    EXPECT_FALSE(Exists("bad")) << c.args;
  }
}

}  // namespace
}  // namespace quijibo
