// Reading, validating and writing meshes; normalization into the unit cube.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>

#include "mesh/normalize.h"
#include "mesh/triangle_mesh.h"
#include "mesh_fixtures.h"
#include "thrown_message.h"
#include "util/error.h"

namespace quijibo::mesh {
namespace {

using testing::TempDir;
using testing::ThrownMessage;

// Unit cube, quads counter-clockwise seen from outside (1-based like OBJ/OFF files).
const char* kCubeVertices = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n";
const int kCubeQuads[6][4] = {{1, 4, 3, 2}, {5, 6, 7, 8}, {1, 2, 6, 5},
                              {4, 8, 7, 3}, {1, 5, 8, 4}, {2, 3, 7, 6}};

std::string CubeObj() {
  std::string s = "# cube\n";
  std::string v = kCubeVertices;
  for (size_t a = 0, b; (b = v.find('\n', a)) != std::string::npos; a = b + 1)
    s += "v " + v.substr(a, b - a) + "\n";
  for (auto& q : kCubeQuads)
    s += "f " + std::to_string(q[0]) + " " + std::to_string(q[1]) + " " + std::to_string(q[2]) +
         " " + std::to_string(q[3]) + "\n";
  return s;
}

std::string CubeQuadList(int base) {
  std::string s;
  for (auto& q : kCubeQuads) {
    s += '4';
    for (int v : q) {
      s += ' ';
      s += std::to_string(v - 1 + base);
    }
    s += '\n';
  }
  return s;
}

TriangleMesh CubeTriangles() {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (auto& q : kCubeQuads) {
    m.triangles.push_back({q[0] - 1, q[1] - 1, q[2] - 1});
    m.triangles.push_back({q[0] - 1, q[2] - 1, q[3] - 1});
  }
  return m;
}

// The cube, as a triangle soup in STL: every corner repeated.
std::string CubeAsciiStl() {
  const TriangleMesh m = CubeTriangles();
  std::string s = "solid cube\n";
  for (auto& t : m.triangles) {
    s += " facet normal 0 0 0\n  outer loop\n";
    for (int v : t)
      s += "   vertex " + std::to_string(m.vertices[v][0]) + " " + std::to_string(m.vertices[v][1]) +
           " " + std::to_string(m.vertices[v][2]) + "\n";
    s += "  endloop\n endfacet\n";
  }
  return s + "endsolid cube\n";
}

std::string CubeBinaryStl() {
  const TriangleMesh m = CubeTriangles();
  std::string s(80, ' ');
  std::memcpy(s.data(), "binary cube", 11);
  const auto n = std::uint32_t(m.triangles.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (auto& t : m.triangles) {
    float f[12] = {};
    for (int c = 0; c < 3; ++c)
      for (int a = 0; a < 3; ++a) f[3 + 3 * c + a] = float(m.vertices[t[c]][a]);
    s.append(reinterpret_cast<const char*>(f), sizeof f);
    s.append(2, '\0');
  }
  return s;
}

void ExpectClosedUnitCube(const TriangleMesh& m) {
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 12u);
  const MeshTopology t = AnalyzeTopology(m);
  EXPECT_TRUE(t.closed());
  EXPECT_EQ(t.misoriented_edges, 0);
  EXPECT_NEAR(t.signed_volume, 1.0, 1e-12);
}

TEST(MeshRead, ObjQuadsAreTriangulated) {
  TempDir dir;
  MeshReadReport report;
  const TriangleMesh m = ReadMesh(dir.write("cube.obj", CubeObj()), &report);
  ExpectClosedUnitCube(m);
  EXPECT_EQ(report.faces_read, 12);
  EXPECT_EQ(report.degenerate_dropped, 0);
}

TEST(MeshRead, AsciiPly) {
  TempDir dir;
  const std::string ply = std::string("ply\nformat ascii 1.0\nelement vertex 8\n") +
                          "property float x\nproperty float y\nproperty float z\n"
                          "element face 6\nproperty list uchar int vertex_indices\nend_header\n" +
                          kCubeVertices + CubeQuadList(0);
  ExpectClosedUnitCube(ReadMesh(dir.write("cube.PLY", ply)));
}

TEST(MeshRead, BinaryPlyWrittenByUs) {
  TempDir dir;
  WritePly(dir.file("cube.ply"), CubeTriangles());
  ExpectClosedUnitCube(ReadMesh(dir.file("cube.ply")));
}

TEST(MeshRead, AsciiStlSoupIsWelded) {
  TempDir dir;
  MeshReadReport report;
  ExpectClosedUnitCube(ReadMesh(dir.write("cube.stl", CubeAsciiStl()), &report));
  EXPECT_EQ(report.corners_welded, 36 - 8);
}

TEST(MeshRead, BinaryStlSoupIsWelded) {
  TempDir dir;
  ExpectClosedUnitCube(ReadMesh(dir.write("cube.stl", CubeBinaryStl())));
}

TEST(MeshRead, Off) {
  TempDir dir;
  ExpectClosedUnitCube(
      ReadMesh(dir.write("cube.off", std::string("OFF\n8 6 0\n") + kCubeVertices + CubeQuadList(0))));
}

TEST(MeshRead, WeldingIsExact) {
  // Two triangles whose shared corner differs in the last float bit must not be joined.
  TempDir dir;
  const float one = 1.0f, next = std::nextafter(1.0f, 2.0f);
  char buf[256];
  std::snprintf(buf, sizeof buf, "v 0 0 0\nv %.9g 0 0\nv 0 1 0\nv %.9g 0 0\nv 0 0 1\nf 1 2 3\nf 1 5 4\n",
                double(one), double(next));
  const TriangleMesh m = ReadMesh(dir.write("near.obj", buf));
  EXPECT_EQ(m.vertices.size(), 5u);
}

TEST(MeshRead, DegenerateFacesAreDroppedAndCounted) {
  TempDir dir;
  MeshReadReport report;
  // A collinear triangle (zero area) and a repeated index next to a real one.
  const TriangleMesh m = ReadMesh(
      dir.write("d.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nf 1 1 4\n"),
      &report);
  EXPECT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.vertices.size(), 3u);
  EXPECT_EQ(report.degenerate_dropped, 2);
}

// Runs ReadMesh and returns the error message ("" if it did not throw).
std::string ReadError(const std::string& path) {
  try {
    ReadMesh(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(MeshRead, BadInputNamesTheFileAndTheElement) {
  TempDir dir;
  std::string msg = ReadError(dir.file("missing.obj"));
  EXPECT_NE(msg.find("missing.obj: no such mesh file"), std::string::npos) << msg;

  msg = ReadError(dir.write("cube.xyz", CubeObj()));
  EXPECT_NE(msg.find("cube.xyz: unknown mesh extension '.xyz'"), std::string::npos) << msg;

  msg = ReadError(dir.write("empty.obj", ""));
  EXPECT_NE(msg.find("empty.obj: file is empty"), std::string::npos) << msg;

  msg = ReadError(dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("nan.obj: vertex 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("non-finite coordinate"), std::string::npos) << msg;

  msg = ReadError(dir.write("inf.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                      "property float y\nproperty float z\nelement face 1\n"
                                      "property list uchar int vertex_indices\nend_header\n"
                                      "0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n"));
  EXPECT_NE(msg.find("inf.ply: vertex 1"), std::string::npos) << msg;

  msg = ReadError(dir.write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"));
  EXPECT_NE(msg.find("range.obj: "), std::string::npos) << msg;

  msg = ReadError(dir.write("range.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                        "property float y\nproperty float z\nelement face 1\n"
                                        "property list uchar int vertex_indices\nend_header\n"
                                        "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"));
  EXPECT_NE(msg.find("range.ply: "), std::string::npos) << msg;

  msg = ReadError(dir.write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"));
  EXPECT_NE(msg.find("points.obj: "), std::string::npos) << msg;

  msg = ReadError(dir.write("flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"));
  EXPECT_NE(msg.find("flat.obj: mesh has no triangles with nonzero area"), std::string::npos) << msg;

  msg = ReadError(dir.write("garbage.stl", std::string("solid x\n this is not an stl\n")));
  EXPECT_NE(msg.find("garbage.stl: "), std::string::npos) << msg;
}

TEST(MeshValidate, IndexOutOfRangeAndNonFinite) {
  TriangleMesh m = CubeTriangles();
  m.triangles[3][1] = 8;
  EXPECT_EQ(ThrownMessage([&] { ValidateMesh(m, "cube"); }), "cube: triangle 3 uses vertex 8, outside [0, 8)");
  m = CubeTriangles();
  m.vertices[5][2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ValidateMesh(m, "cube"), Error);
}

// Same triangles in the same order with the same corner positions (up to `tolerance`);
// vertex numbering may differ, since ReadMesh numbers vertices by first use.
void ExpectSameGeometry(const TriangleMesh& a, const TriangleMesh& b, double tolerance) {
  ASSERT_EQ(a.triangles.size(), b.triangles.size());
  EXPECT_EQ(a.vertices.size(), b.vertices.size());
  for (size_t t = 0; t < a.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      for (int x = 0; x < 3; ++x)
        ASSERT_NEAR(a.vertices[a.triangles[t][c]][x], b.vertices[b.triangles[t][c]][x], tolerance)
            << "triangle " << t << " corner " << c;
}

TriangleMesh RoundedToFloat(TriangleMesh m) {
  // volatile: GCC 12's -O3 loop vectorizer folds double(float(x)) back to x here.
  for (Vec3& p : m.vertices)
    for (double& x : p) {
      volatile float f = float(x);
      x = f;
    }
  return m;
}

TEST(MeshWrite, PlyRoundTrip) {
  TempDir dir;
  const TriangleMesh sphere = testing::Icosphere(3, {0.1, -0.2, 0.3}, 0.7);
  WritePly(dir.file("d.ply"), sphere, PlyPrecision::kFloat64);
  // assimp carries coordinates in float: the double file reads back to float precision.
  ExpectSameGeometry(ReadMesh(dir.file("d.ply")), RoundedToFloat(sphere), 0.0);
  WritePly(dir.file("f.ply"), sphere);
  ExpectSameGeometry(ReadMesh(dir.file("f.ply")), RoundedToFloat(sphere), 0.0);
  // Our own reading of the bytes: header, then float32 xyz, then uchar 3 + int32 x 3.
  const std::string bytes = [&] {
    std::ifstream in(dir.file("f.ply"), std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }();
  const size_t body = bytes.find("end_header\n") + 11;
  ASSERT_EQ(bytes.size(), body + 12 * sphere.vertices.size() + 13 * sphere.triangles.size());
  float x;
  std::memcpy(&x, bytes.data() + body + 12 * 5 + 4, 4);
  EXPECT_EQ(x, float(sphere.vertices[5][1]));
  std::int32_t v;
  std::memcpy(&v, bytes.data() + body + 12 * sphere.vertices.size() + 13 * 7 + 1 + 4, 4);
  EXPECT_EQ(v, sphere.triangles[7][1]);
  EXPECT_EQ(dir.count(), 2u);  // no temporary files left
}

TEST(MeshWrite, ObjRoundTrip) {
  TempDir dir;
  const TriangleMesh sphere = testing::Icosphere(2);
  WriteObj(dir.file("s.obj"), sphere);
  ExpectSameGeometry(ReadMesh(dir.file("s.obj")), sphere, 1e-7);
}

TEST(MeshTopology, HoleAndMisorientation) {
  TriangleMesh m = testing::Icosphere(1);
  EXPECT_TRUE(AnalyzeTopology(m).closed());
  EXPECT_GT(AnalyzeTopology(m).signed_volume, 3.5);  // inscribed in the unit ball
  EXPECT_LT(AnalyzeTopology(m).signed_volume, 4.0 / 3.0 * M_PI);
  m.triangles.pop_back();
  EXPECT_EQ(AnalyzeTopology(m).boundary_edges, 3);
  std::swap(m.triangles[0][1], m.triangles[0][2]);
  EXPECT_EQ(AnalyzeTopology(m).misoriented_edges, 3 - 0);
}

TEST(Normalization, BunnyFillsTheReferenceBox) {
  const TriangleMesh bunny = ReadMesh(QUIJIBO_SOURCE_DIR "/data/bunny.obj");
  EXPECT_EQ(bunny.triangles.size(), 3674u);
  const FractalFrame frame = NormalizationFor(bunny);
  EXPECT_EQ(frame.padding, 0.125);
  EXPECT_EQ(frame.fractal_radius, 4.0);
  TriangleMesh unit = bunny;
  for (Vec3& p : unit.vertices)
    for (int a = 0; a < 3; ++a) p[a] = frame.scale * p[a] + frame.translation[a];
  const BoundingBox box = ComputeBoundingBox(unit);
  double longest = 0.0;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(0.5 * (box.min[a] + box.max[a]), 0.5, 1e-12);
    EXPECT_GE(box.min[a], 0.125 - 1e-12);
    EXPECT_LE(box.max[a], 0.875 + 1e-12);
    longest = std::max(longest, box.max[a] - box.min[a]);
  }
  EXPECT_NEAR(longest, 0.75, 1e-12);

  // Fractal frame: centred at 0, longest side 4 * 0.75 = 3; and back to the user's mesh.
  const TriangleMesh w = ToFractalFrame(bunny, frame);
  const BoundingBox wb = ComputeBoundingBox(w);
  double wl = 0.0;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(wb.min[a] + wb.max[a], 0.0, 1e-12);
    wl = std::max(wl, wb.max[a] - wb.min[a]);
  }
  EXPECT_NEAR(wl, 3.0, 1e-12);
  const TriangleMesh back = FromFractalFrame(w, frame);
  for (size_t v = 0; v < back.vertices.size(); ++v)
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(back.vertices[v][a], bunny.vertices[v][a], 1e-12);
}

TEST(Normalization, RejectsPointMeshAndBadPadding) {
  TriangleMesh m;
  m.vertices = {{1, 1, 1}};
  EXPECT_THROW(NormalizationFor(m), Error);
  EXPECT_THROW(NormalizationFor(CubeTriangles(), 0.5), Error);
  EXPECT_THROW(NormalizationFor(CubeTriangles(), 0.1, -1.0), Error);
}

}  // namespace
}  // namespace quijibo::mesh
