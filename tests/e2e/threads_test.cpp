// Determinism across thread counts: `monopoles` (both initializers), `optimize` (a few hundred
// iterations, both evaluators) and `mesh` write the same bytes with OMP_NUM_THREADS=1 and 2 (apart
// from wall-clock fields), so a result does not depend on the machine it ran on.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "output_compare.h"
#include "quijibo_command.h"

namespace {

namespace fs = std::filesystem;
using quijibo::testing::ExpectSameOutputs;
using quijibo::testing::RunQuijibo;

std::string Fresh(const std::string& name) {
  const std::string d = (fs::temp_directory_path() / ("quijibo_threads_" + name)).string();
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

// Runs `args` (with OUT standing for the output folder) once per thread count and compares.
void ExpectSameWithOneAndTwoThreads(const std::string& name, const std::string& args) {
  const std::string dir = Fresh(name);
  for (const char* threads : {"1", "2"}) {
    const std::string out = dir + "/t" + threads;
    fs::create_directories(out);
    std::string a = args;
    for (std::size_t k; (k = a.find("OUT")) != std::string::npos;) a.replace(k, 3, out);
    const auto r = RunQuijibo(a, std::string("OMP_NUM_THREADS=") + threads);
    ASSERT_EQ(r.code, 0) << threads << " threads: " << r.out;
  }
  ExpectSameOutputs(dir + "/t1", dir + "/t2");
  fs::remove_all(dir);
}

const std::string kBunny = std::string(QUIJIBO_SOURCE_DIR) + "/data/bunny.obj";

TEST(ThreadCount, LogKernelStartIsTheSame) {
  ExpectSameWithOneAndTwoThreads("kernel", "monopoles " + kBunny + " -o OUT/m -r 32 --roots 120 --png-size 48");
}

TEST(ThreadCount, MonopoleStartIsTheSame) {
  ExpectSameWithOneAndTwoThreads("monopoles", "monopoles " + kBunny +
                                                  " -o OUT/m -r 25 --initializer monopoles --candidates 5000"
                                                  " --bem-elements 400 --png-size 48");
}

TEST(ThreadCount, OptimizeIsTheSame) {
  const std::string dir = Fresh("map");
  const std::string map = dir + "/init.json";
  ASSERT_EQ(RunQuijibo("map random --top 40 --bottom 30 --seed 5 --center-on torus --target-resolution 24 -o " + map)
                .code,
            0);
  // A few hundred iterations with the default (log-linear) evaluator, fewer with the cached one.
  ExpectSameWithOneAndTwoThreads("loglinear", "optimize -t torus --target-resolution 24 -m " + map +
                                                  " -s '12(VFRF)24(VF)' --weights layer --max-v 60 --max-f 120 --max-r 40 -o OUT/o");
  ExpectSameWithOneAndTwoThreads("cached", "optimize -t torus --target-resolution 24 -m " + map +
                                               " -s '12(VF)' --max-f 40 -e cached -o OUT/o");
  fs::remove_all(dir);
}

TEST(ThreadCount, MeshIsTheSame) {
  const std::string dir = Fresh("mesh_map");
  const std::string map = dir + "/map.json";
  ASSERT_EQ(RunQuijibo("map random --top 12 --bottom 8 --seed 2 -o " + map).code, 0);
  ExpectSameWithOneAndTwoThreads("mesh", "mesh " + map +
                                             " -o OUT/julia.ply -r 48 -n 2 --vdb OUT/julia.vdb --obj OUT/julia.obj"
                                             " --summary OUT/summary.json --allow-empty");
  fs::remove_all(dir);
}

}  // namespace
