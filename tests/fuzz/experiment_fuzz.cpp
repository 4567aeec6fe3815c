// libFuzzer target: the experiment parser (pipeline::Experiment: JSON parsing, validation with JSON
// pointers, defaults, the resolved form). The input is the experiment file; it sits in a folder that also holds a
// small mesh ("bunny.obj"), a schedule ("schedule.json") and a versor polynomial ("poly.json"), so
// relative references can resolve.
// A quijibo::Error is the expected refusal; any other exception, a crash or a sanitizer report is
// a bug.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>

#include "experiments/pipeline/experiment.h"
#include "fuzz_input_file.h"
#include "util/error.h"

namespace {
void PrepareFolder() {
  static const bool done = [] {
    const auto folder = quijibo::fuzz::ScratchFolder();
    std::ofstream(folder / "bunny.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::ofstream(folder / "schedule.json") << R"({"levels": [{"resolution": 9, "passes": [{"kind": "V", "max_iterations": 5}]}]})";
    std::filesystem::copy_file(QUIJIBO_SOURCE_DIR "/data/sm-baseline-poly10.json", folder / "poly.json",
                               std::filesystem::copy_options::overwrite_existing);
    return true;
  }();
  (void)done;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  PrepareFolder();
  const std::string path = quijibo::fuzz::WriteInput("experiment.json", data, size);
  try {
    const nlohmann::json resolved = quijibo::pipeline::Experiment::FromFile(path).ToJson();
    if (!resolved.is_object()) std::abort();
  } catch (const quijibo::Error&) {
    // refused with a message: fine
  } catch (const std::exception& e) {
    std::fprintf(stderr, "the experiment parser threw a non-quijibo exception: %s\n", e.what());
    std::abort();
  }
  return 0;
}
