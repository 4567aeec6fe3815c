// libFuzzer target: ReadMesh (OBJ, PLY, STL, OFF through assimp, then our weld and validation).
// The first byte picks the extension, the rest is the file. A quijibo::Error is the expected way
// to refuse a file; any other exception, a crash, a sanitizer report or a mesh that breaks the
// documented guarantees (finite coordinates, indices in range, no degenerate triangle) is a bug.
// docs/fuzzing.md says how to run it.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <exception>

#include "fuzz_input_file.h"
#include "mesh/triangle_mesh.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  static const char* const kNames[] = {"input.obj", "input.ply", "input.stl", "input.off"};
  const std::string path = quijibo::fuzz::WriteInput(kNames[data[0] % 4], data + 1, size - 1);
  try {
    quijibo::mesh::MeshReadReport report;
    const quijibo::mesh::TriangleMesh mesh = quijibo::mesh::ReadMesh(path, &report);
    if (mesh.triangles.empty()) std::abort();
    const auto n = std::int64_t(mesh.vertices.size());
    for (const auto& v : mesh.vertices)
      for (double x : v)
        if (!std::isfinite(x)) std::abort();
    for (const auto& t : mesh.triangles) {
      for (int v : t)
        if (v < 0 || v >= n) std::abort();
      if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) std::abort();
    }
    if (report.faces_read < std::int64_t(mesh.triangles.size())) std::abort();
  } catch (const quijibo::Error&) {
    // refused with a message: fine
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ReadMesh threw a non-quijibo exception: %s\n", e.what());
    std::abort();
  }
  return 0;
}
