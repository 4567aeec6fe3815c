// Streamed meshing (mesh/mesh_stream.h): the same PLY bytes and the same summary as the in-memory
// mesh for several tile sizes, thread counts and modes; the 64-bit index path read back by our reader
// and by NumPy; no file left behind on failure.
#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mesh/marching_cubes.h"
#include "mesh/mesh_stream.h"
#include "mesh/triangle_mesh.h"
#include "mesh_fixtures.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::mesh {
namespace {

using testing::Lambda;
using testing::TempDir;

// A porous field cut open by the box (open edges on the box faces), many components, and one-node
// specks and bubbles on and beside the tile seams (z = -1, 0, 1 are seams of tiles of 8 and 16 cells
// at 64 cells on [-2, 2]^3), so that the front's speck, component and open-edge passes are all tested.
BatchField Porous() {
  return Lambda([](const Vec3& p) {
    auto node = [&](double x, double y, double z) {
      return std::abs(p[0] - x) < 1e-9 && std::abs(p[1] - y) < 1e-9 && std::abs(p[2] - z) < 1e-9;
    };
    const double g = std::sin(4 * p[0] + 0.3) * std::cos(4 * p[1]) + std::sin(4 * p[1]) * std::cos(4 * p[2] + 0.1) +
                     std::sin(4 * p[2]) * std::cos(4 * p[0]) + 0.35 * std::sin(9 * p[0] * p[1] + 2 * p[2]);
    // Nodes whose 26 neighbours are all on one side, at least 3 cells apart (so each is one speck).
    for (const auto& [x, z] : {std::pair{-1.375, -1.0}, {-0.8125, -0.9375}, {-1.5625, 0.0}, {-1.375, 0.0625},
                               {-1.75, 1.0}, {-1.5625, 0.9375}, {-1.1875, -0.0625}, {-1.5625, -1.0625}})
      if (node(x, 1.75, z)) return g > 0 ? -1.0 : 1.0;  // the node alone on the other side
    return g;
  });
}

std::string Bytes(const std::string& path) { return ReadFile(path); }

struct Case {
  int tile;
  int threads;
  bool sparse;
};

TEST(MeshStream, SameBytesAndSummaryAsInMemory) {
  TempDir dir;
  const int saved = omp_get_max_threads();
  for (const Case c : {Case{8, 1, true}, Case{8, 2, true}, Case{16, 2, true}, Case{4, 1, true}, Case{16, 1, false},
                       Case{32, 2, false}}) {
    SCOPED_TRACE("tile " + std::to_string(c.tile) + ", threads " + std::to_string(c.threads) +
                 (c.sparse ? ", sparse" : ", dense"));
    omp_set_num_threads(c.threads);
    MeshingOptions o;
    o.resolution = 64;
    o.tile_cells = c.tile;
    o.sparse = c.sparse;
    o.search_min_cells = 16;
    MeshingSummary sm, ss;
    const TriangleMesh m = MeshField(Porous(), o, &sm);
    WritePly(dir.file("memory.ply"), m);
    MeshStreamOptions so;
    so.path = dir.file("stream.ply");
    const MeshStreamReport r = MeshFieldStreamed(Porous(), o, so, &ss);
    ASSERT_EQ(Bytes(dir.file("memory.ply")), Bytes(dir.file("stream.ply")));
    EXPECT_EQ(r.index_type, "int");
    EXPECT_EQ(r.bytes, std::int64_t(std::filesystem::file_size(dir.file("stream.ply"))));
    if (!c.sparse) {
      EXPECT_GE(sm.specks_removed, 8) << "the field's specks (the sparse search may miss some)";
    }
    EXPECT_EQ(ss.specks_removed, sm.specks_removed);
    EXPECT_GT(sm.components, 2);
    EXPECT_EQ(ss.components, sm.components);
    EXPECT_GT(sm.open_edges, 0);
    EXPECT_EQ(ss.open_edges, sm.open_edges);
    EXPECT_EQ(ss.open_edges_inside, sm.open_edges_inside);
    EXPECT_EQ(r.non_manifold_edges, AnalyzeTopology(m).non_manifold_edges);
    EXPECT_EQ(ss.vertices, sm.vertices);
    EXPECT_EQ(ss.triangles, sm.triangles);
    EXPECT_EQ(ss.nodes_evaluated, sm.nodes_evaluated);
    EXPECT_EQ(ss.bisection_evaluations, sm.bisection_evaluations);
    EXPECT_EQ(ss.blocks_active, sm.blocks_active);
    if (c.tile <= 16) {
      EXPECT_LT(r.peak_front_triangles, std::int64_t(m.triangles.size())) << "the front is less than the mesh";
    }
    // Specks kept: the same too.
    o.remove_specks = false;
    WritePly(dir.file("memory.ply"), MeshField(Porous(), o, &sm));
    MeshFieldStreamed(Porous(), o, so, &ss);
    ASSERT_EQ(Bytes(dir.file("memory.ply")), Bytes(dir.file("stream.ply")));
    EXPECT_EQ(ss.components, sm.components) << "specks kept: one component each";
    EXPECT_EQ(ss.open_edges, sm.open_edges);
  }
  omp_set_num_threads(saved);
  EXPECT_EQ(dir.count(), 2u) << "no scratch or temporary file left";
}

TEST(MeshStream, DoublePrecisionAndTransform) {
  TempDir dir;
  MeshingOptions o;
  o.resolution = 48;
  o.tile_cells = 8;
  auto move = [](const Vec3& v) { return Vec3{2 * v[1] + 0.1, v[0] - 3, 0.5 * v[2]}; };
  TriangleMesh m = MeshField(Porous(), o);
  for (Vec3& v : m.vertices) v = move(v);
  WritePly(dir.file("memory.ply"), m, PlyPrecision::kFloat64);
  MeshStreamOptions so;
  so.path = dir.file("stream.ply");
  so.precision = PlyPrecision::kFloat64;
  so.transform = move;
  MeshFieldStreamed(Porous(), o, so, nullptr);
  EXPECT_EQ(Bytes(dir.file("memory.ply")), Bytes(dir.file("stream.ply")));
}

// The 64-bit path on a small mesh: indices as uint64, read back by ReadBinaryPly and by NumPy.
TEST(MeshStream, SixtyFourBitIndicesReadBack) {
  TempDir dir;
  MeshingOptions o;
  o.resolution = 32;
  o.tile_cells = 8;
  const TriangleMesh m = MeshField(Porous(), o);
  WritePly(dir.file("memory.ply"), m);
  MeshStreamOptions so;
  so.path = dir.file("wide.ply");
  so.index_bits = 64;
  const MeshStreamReport r = MeshFieldStreamed(Porous(), o, so, nullptr);
  EXPECT_EQ(r.index_type, "uint64");
  const std::string bytes = Bytes(so.path);
  EXPECT_NE(bytes.find("property list uchar uint64 vertex_indices\n"), std::string::npos);
  EXPECT_EQ(bytes.size(), Bytes(dir.file("memory.ply")).size() + 3 + 12 * m.triangles.size());  // "uint64" for "int"
  const IndexedMesh64 narrow = ReadBinaryPly(dir.file("memory.ply")), wide = ReadBinaryPly(so.path);
  EXPECT_EQ(narrow.index_type, "int");
  EXPECT_EQ(wide.index_type, "uint64");
  ASSERT_EQ(wide.vertices.size(), m.vertices.size());
  ASSERT_EQ(wide.triangles.size(), m.triangles.size());
  EXPECT_EQ(wide.vertices, narrow.vertices);
  EXPECT_EQ(wide.triangles, narrow.triangles);
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) ASSERT_EQ(wide.triangles[t][std::size_t(c)], std::uint64_t(m.triangles[t][std::size_t(c)]));

  // NumPy parses the header and reads the faces as a structured array of uint64 triples.
  if (std::system("/usr/bin/python3 -c 'import numpy' 2>/dev/null") != 0) GTEST_SKIP() << "no python3 with NumPy";
  const std::string script = dir.write("read.py", R"(import sys, numpy as np
data = open(sys.argv[1], 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
header = data[:end].decode().split('\n')
nv = int([l for l in header if l.startswith('element vertex')][0].split()[2])
nf = int([l for l in header if l.startswith('element face')][0].split()[2])
assert 'property list uchar uint64 vertex_indices' in header
v = np.frombuffer(data, dtype='<f4', count=3 * nv, offset=end).reshape(nv, 3)
f = np.frombuffer(data, dtype=np.dtype([('n', 'u1'), ('i', '<u8', 3)]), count=nf, offset=end + 12 * nv)
assert (f['n'] == 3).all() and f['i'].max() < nv and end + 12 * nv + 25 * nf == len(data)
print(nv, nf, int(f['i'].astype(np.uint64).sum()), '%.6f' % float(v.astype(np.float64).sum()))
)");
  const std::string cmd = "/usr/bin/python3 " + script + " " + so.path;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buf[256] = {};
  const std::string out = std::fgets(buf, sizeof buf, pipe) ? buf : "";
  ASSERT_EQ(::pclose(pipe), 0) << out;
  std::uint64_t sum = 0;
  double vsum = 0;
  for (const auto& t : m.triangles)
    for (int i : t) sum += std::uint64_t(i);
  for (const auto& v : narrow.vertices)
    for (double x : v) vsum += x;
  std::istringstream s(out);
  std::uint64_t nv = 0, nf = 0, isum = 0;
  double psum = 0;
  s >> nv >> nf >> isum >> psum;
  EXPECT_EQ(nv, m.vertices.size());
  EXPECT_EQ(nf, m.triangles.size());
  EXPECT_EQ(isum, sum);
  EXPECT_NEAR(psum, vsum, 1e-3 + 1e-9 * std::abs(vsum));
}

// The largest index is vertices - 1: int holds it up to 2^31 vertices, uint up to 2^32.
TEST(MeshStream, IndexTypeByVertexCount) {
  const std::uint64_t two31 = std::uint64_t(1) << 31, two32 = std::uint64_t(1) << 32;
  EXPECT_EQ(PlyIndexType(3), "int");
  EXPECT_EQ(PlyIndexType(two31), "int");
  EXPECT_EQ(PlyIndexType(two31 + 1), "uint");
  EXPECT_EQ(PlyIndexType(two32), "uint");
  EXPECT_EQ(PlyIndexType(two32 + 1), "uint64");
  EXPECT_EQ(PlyIndexType(3, 64), "uint64");
}

TEST(MeshStream, FailureLeavesNoFile) {
  TempDir dir;
  MeshingOptions o;
  o.resolution = 32;
  o.tile_cells = 8;
  const std::string old = dir.write("out.ply", "the previous file");
  MeshStreamOptions so;
  so.path = old;
  int pieces = 0;
  so.band = [&pieces](const TilePiece&) {
    if (++pieces == 5) throw Error("disk full (a test)");
  };
  EXPECT_THROW(MeshFieldStreamed(Porous(), o, so, nullptr), Error);
  EXPECT_EQ(Bytes(old), "the previous file") << "the old file is untouched";
  EXPECT_EQ(dir.count(), 1u) << "no scratch, no partial file";
  // A writer dropped before Finish leaves nothing either.
  {
    const TilePlan plan = PlanTiles(Porous(), o);
    MeshStreamOptions s2;
    s2.path = dir.file("never.ply");
    MeshStreamWriter w(plan, s2);
    w.Add(0, MeshTilePiece(Porous(), plan, 0, false));
    EXPECT_THROW(w.Finish(nullptr), Error) << "tiles missing";
  }
  EXPECT_EQ(dir.count(), 1u);
}

TEST(MeshStream, PiecesInAnyOrderAndBadInput) {
  TempDir dir;
  MeshingOptions o;
  o.resolution = 32;
  o.tile_cells = 8;
  const TilePlan plan = PlanTiles(Porous(), o);
  MeshStreamOptions so;
  so.path = dir.file("reverse.ply");
  {
    MeshStreamWriter w(plan, so);
    for (std::size_t i = plan.tile_ids.size(); i-- > 0;) w.Add(i, MeshTilePiece(Porous(), plan, i, false));
    EXPECT_THROW(w.Add(0, MeshTilePiece(Porous(), plan, 0, false)), Error) << "a repeated piece";
    w.Finish(nullptr);
  }
  WritePly(dir.file("memory.ply"), MeshField(Porous(), o));
  EXPECT_EQ(Bytes(dir.file("memory.ply")), Bytes(so.path));
  MeshStreamOptions bad;
  bad.path = dir.file("x.obj");
  EXPECT_THROW(MeshStreamWriter(plan, bad), Error);
  // No surface in the box: no file, zero triangles.
  MeshingSummary s;
  so.path = dir.file("empty.ply");
  MeshFieldStreamed(Lambda([](const Vec3&) { return 1.0; }), o, so, &s);
  EXPECT_EQ(s.triangles, 0);
  EXPECT_FALSE(std::filesystem::exists(so.path));
}

}  // namespace
}  // namespace quijibo::mesh
