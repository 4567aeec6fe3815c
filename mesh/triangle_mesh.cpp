#include "mesh/triangle_mesh.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <unordered_map>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>

#include "util/error.h"
#include "util/io.h"

namespace quijibo::mesh {

static_assert(std::endian::native == std::endian::little,
              "WritePly writes native little-endian bytes");

namespace {

std::string Lowercase(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string FormatVec(const Vec3& v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "(%g, %g, %g)", v[0], v[1], v[2]);
  return buf;
}

// Hash of a position by its bits; -0.0 is folded into +0.0 before hashing so both weld.
struct PositionHash {
  std::size_t operator()(const Vec3& p) const {
    std::size_t h = 0;
    for (double x : p) h = h * 0x9E3779B97F4A7C15ull ^ std::bit_cast<std::uint64_t>(x);
    return h ^ (h >> 29);
  }
};

Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

bool IsDegenerate(const TriangleMesh& mesh, const std::array<int, 3>& t) {
  if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return true;
  const Vec3 n = Cross(Sub(mesh.vertices[t[1]], mesh.vertices[t[0]]),
                       Sub(mesh.vertices[t[2]], mesh.vertices[t[0]]));
  return n[0] == 0.0 && n[1] == 0.0 && n[2] == 0.0;
}

// Appends the triangles of `node` and its children, welding corners by exact position.
void CollectNode(const aiScene& scene, const aiNode& node, const aiMatrix4x4& parent,
                 const std::string& path, TriangleMesh& mesh,
                 std::unordered_map<Vec3, int, PositionHash>& index_of, MeshReadReport& report) {
  const aiMatrix4x4 transform = parent * node.mTransformation;
  const bool identity = transform.IsIdentity();
  for (unsigned m = 0; m < node.mNumMeshes; ++m) {
    const aiMesh& am = *scene.mMeshes[node.mMeshes[m]];
    for (unsigned f = 0; f < am.mNumFaces; ++f) {
      const aiFace& face = am.mFaces[f];
      if (face.mNumIndices < 3 || face.mIndices == nullptr) {
        ++report.non_triangles_ignored;
        continue;
      }
      // Polygons as fans (0, k, k+1): the same boundary, so the same winding numbers for the SDF.
      // (assimp's own triangulation aborts on some malformed files; found by fuzzing.)
      for (unsigned k = 1; k + 1 < face.mNumIndices; ++k) {
        std::array<int, 3> tri;
        const unsigned corner[3] = {0, k, k + 1};
        for (int c = 0; c < 3; ++c) {
          const unsigned vi = face.mIndices[corner[c]];
          if (vi >= am.mNumVertices)
            throw Error(path + ": face " + std::to_string(report.faces_read) + " uses vertex " +
                        std::to_string(vi) + " but the mesh has " +
                        std::to_string(am.mNumVertices) + " vertices");
          aiVector3D a = am.mVertices[vi];
          if (!identity) a = transform * a;
          Vec3 p{double(a.x) + 0.0, double(a.y) + 0.0, double(a.z) + 0.0};  // +0.0 folds -0.0
          if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
            throw Error(path + ": vertex " + std::to_string(mesh.vertices.size()) +
                        " (used by face " + std::to_string(report.faces_read) +
                        ") has a non-finite coordinate " + FormatVec(p));
          }
          auto [it, inserted] = index_of.try_emplace(p, int(mesh.vertices.size()));
          if (inserted)
            mesh.vertices.push_back(p);
          else
            ++report.corners_welded;
          tri[c] = it->second;
        }
        mesh.triangles.push_back(tri);
        ++report.faces_read;
      }
    }
  }
  for (unsigned c = 0; c < node.mNumChildren; ++c)
    CollectNode(scene, *node.mChildren[c], transform, path, mesh, index_of, report);
}

template <typename T>
void Put(char*& out, T value) {
  std::memcpy(out, &value, sizeof(T));
  out += sizeof(T);
}

std::string FormatCount(double n) {
  std::ostringstream s;
  s << std::setprecision(n < 1e15 ? 15 : 3) << n;
  return s.str();
}

// The first 64 KiB of a file.
std::string FileHead(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(64 * 1024, '\0');
  in.read(head.data(), std::streamsize(head.size()));
  head.resize(std::size_t(in.gcount()));
  return head;
}

// Element counts a header promises must fit the file: assimp allocates for them before reading
// (an OFF file claiming 10^100 faces made it ask for 68 GB; found by fuzzing). `min_bytes` is the
// smallest size one element can have in any encoding.
void CheckCount(const std::string& path, const std::string& what, double count, double min_bytes, std::uintmax_t size) {
  if (!(count >= 0) || count * min_bytes > double(size))
    throw Error(path + ": the header promises " + FormatCount(count) + " " + what + ", more than the file's " +
                std::to_string(size) + " bytes can hold");
}

// OFF: a magic word containing "OFF" (assimp takes "OFF", "COFF", "NOFF", "OFF8", ...), then the
// vertex and face counts, on the same line or the next one that is not blank or a comment. They
// are read as doubles, so a number too large for assimp's 32 bits is refused, not wrapped.
void CheckOffHeader(const std::string& path, std::uintmax_t size) {
  std::istringstream in(FileHead(path));
  std::string line;
  if (!std::getline(in, line)) return;
  const auto start = line.find_first_not_of(" \t\r");
  if (start == std::string::npos) return;
  const auto stop = std::min(line.find_first_of(" \t\r", start), line.size());
  if (line.substr(start, stop - start).find("OFF") == std::string::npos) return;  // assimp will say
  std::string rest = line.substr(stop);
  auto blank = [](std::string& t) {
    if (const auto hash = t.find('#'); hash != std::string::npos) t.resize(hash);
    return t.find_first_not_of(" \t\r") == std::string::npos;
  };
  while (blank(rest))
    if (!std::getline(in, rest)) return;
  const char* p = rest.c_str();
  char* end = nullptr;
  const double vertices = std::strtod(p, &end);
  if (end == p) return;
  CheckCount(path, "vertices", vertices, 6.0, size);  // "0 0 0\n"
  p = end;
  const double faces = std::strtod(p, &end);
  if (end != p) CheckCount(path, "faces", faces, 8.0, size);  // "3 0 1 2\n"
}

// Debian's assimp 5.2 loops forever on a PLY whose header never ends (found by fuzzing,
// docs/fuzzing.md), so the header is checked first: "ply", then an "end_header" line within 64 KiB;
// and the element counts must fit the file.
void CheckPlyHeader(const std::string& path, std::uintmax_t size) {
  const std::string head = FileHead(path);
  if (head.rfind("ply", 0) != 0 || (head.size() > 3 && head[3] != '\n' && head[3] != '\r'))
    throw Error(path + ": not a PLY file (it must start with a line \"ply\")");
  std::size_t at = 0;
  while ((at = head.find("end_header", at)) != std::string::npos) {
    const bool line_start = at > 0 && head[at - 1] == '\n';
    const std::size_t after = at + 10;
    const bool line_end = after < head.size() && (head[after] == '\n' || head[after] == '\r');
    if (line_start && line_end) break;
    at = after;
  }
  if (at == std::string::npos) throw Error(path + ": PLY header has no \"end_header\" line in its first 64 KiB");
  // Each element needs at least one byte per property (binary uchar; ASCII needs more).
  std::istringstream header(head.substr(0, at));
  std::string line, name;
  double count = -1, properties = 0;
  auto flush = [&] {
    if (count >= 0) CheckCount(path, name + " elements", count, std::max(1.0, properties), size);
  };
  while (std::getline(header, line)) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "element") {
      flush();
      words >> name >> count;
      if (!words) count = -1;
      properties = 0;
    } else if (word == "property") {
      ++properties;
    }
  }
  flush();
}

// assimp's import and our collection of its triangles (welded by exact position).
void ImportWithAssimp(const std::string& path, TriangleMesh& mesh, MeshReadReport& report) {
  // No post-processing but validation: no welding with tolerances, no reordering, no normals;
  // polygons are triangulated by CollectNode.
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  if (scene == nullptr || scene->mRootNode == nullptr) {
    std::string why = importer.GetErrorString();
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw Error(path + ": cannot read mesh: " + (why.empty() ? "unknown assimp error" : why));
  }
  std::unordered_map<Vec3, int, PositionHash> index_of;
  CollectNode(*scene, *scene->mRootNode, aiMatrix4x4(), path, mesh, index_of, report);
}

bool WriteAll(int fd, const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= std::size_t(w);
  }
  return true;
}

// Runs ImportWithAssimp in a child process and takes its result through a pipe. assimp 5.2 (Debian)
// hangs, aborts on internal asserts and corrupts its heap on some malformed files (found by
// fuzzing, docs/fuzzing.md); in a child, each of these becomes an error naming the file instead of
// a crash of quijibo. A hang is ended by a CPU-time limit.
void ImportIsolated(const std::string& path, std::uintmax_t size, TriangleMesh& mesh, MeshReadReport& report) {
  int fds[2];
  if (::pipe(fds) != 0) throw Error(path + ": cannot read mesh: pipe: " + std::strerror(errno));
  const double megabytes = double(size) / 1e6;
  const rlim_t cpu_seconds = rlim_t(120.0 + 20.0 * megabytes);
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  if (pid < 0) throw Error(path + ": cannot read mesh: fork: " + std::strerror(errno));
  if (pid == 0) {
    ::close(fds[0]);
    const rlimit limit{cpu_seconds, cpu_seconds + 5};
    ::setrlimit(RLIMIT_CPU, &limit);
    std::string message;
    TriangleMesh m;
    MeshReadReport r;
    try {
      ImportWithAssimp(path, m, r);
    } catch (const Error& e) {
      message = e.what();
    } catch (const std::exception& e) {
      message = path + ": cannot read mesh: " + e.what();
    }
    // Header: failed?, message size, vertices, triangles, the report; then the message or the arrays.
    const std::int64_t head[7] = {message.empty() ? 0 : 1,        std::int64_t(message.size()),
                                  std::int64_t(m.vertices.size()), std::int64_t(m.triangles.size()),
                                  r.faces_read,                     r.non_triangles_ignored,
                                  r.corners_welded};
    bool ok = WriteAll(fds[1], head, sizeof head) && WriteAll(fds[1], message.data(), message.size());
    if (ok && message.empty())
      ok = WriteAll(fds[1], m.vertices.data(), m.vertices.size() * sizeof(Vec3)) &&
           WriteAll(fds[1], m.triangles.data(), m.triangles.size() * sizeof(std::array<int, 3>));
    ::_exit(ok ? 0 : 3);
  }
  ::close(fds[1]);
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    bytes.append(buffer, std::size_t(n));
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    if (sig == SIGXCPU || sig == SIGKILL)
      throw Error(path + ": cannot read mesh: the importer (assimp) ran for more than " + std::to_string(cpu_seconds) +
                  " CPU seconds; the file is probably malformed");
    throw Error(path + ": cannot read mesh: the importer (assimp) crashed on this file (" + strsignal(sig) +
                "); the file is probably malformed");
  }
  std::int64_t head[7];
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || bytes.size() < sizeof head)
    throw Error(path + ": cannot read mesh: the importer process failed");
  std::memcpy(head, bytes.data(), sizeof head);
  std::size_t at = sizeof head;
  const auto message_size = std::size_t(head[1]);
  if (head[0] != 0) throw Error(bytes.substr(at, message_size));
  const auto nv = std::size_t(head[2]), nt = std::size_t(head[3]);
  if (bytes.size() != at + nv * sizeof(Vec3) + nt * sizeof(std::array<int, 3>))
    throw Error(path + ": cannot read mesh: the importer process returned a truncated result");
  mesh.vertices.resize(nv);
  mesh.triangles.resize(nt);
  if (nv) std::memcpy(mesh.vertices.data(), bytes.data() + at, nv * sizeof(Vec3));
  at += nv * sizeof(Vec3);
  if (nt) std::memcpy(mesh.triangles.data(), bytes.data() + at, nt * sizeof(std::array<int, 3>));
  report.faces_read = head[4];
  report.non_triangles_ignored = head[5];
  report.corners_welded = head[6];
}

}  // namespace

TriangleMesh ReadMesh(const std::string& path, MeshReadReport* report_out) {
  const std::string ext = Lowercase(std::filesystem::path(path).extension().string());
  if (ext != ".obj" && ext != ".ply" && ext != ".stl" && ext != ".off")
    throw Error(path + ": unknown mesh extension '" + ext +
                "' (expected .obj, .ply, .stl or .off)");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw Error(path + ": no such mesh file");
  if (!std::ifstream(path, std::ios::binary).good()) throw Error(path + ": cannot open file");
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (size == 0) throw Error(path + ": file is empty");

  if (ext == ".ply") CheckPlyHeader(path, size);
  if (ext == ".off") CheckOffHeader(path, size);

  TriangleMesh mesh;
  MeshReadReport report;
  ImportIsolated(path, size, mesh, report);
  if (mesh.triangles.empty())
    throw Error(path + ": mesh has no triangles" +
                (report.non_triangles_ignored
                     ? " (" + std::to_string(report.non_triangles_ignored) +
                           " point or line primitives ignored)"
                     : std::string()));
  report.degenerate_dropped = RemoveDegenerateTriangles(mesh);
  if (mesh.triangles.empty())
    throw Error(path + ": mesh has no triangles with nonzero area (all " +
                std::to_string(report.degenerate_dropped) + " are degenerate)");
  // Welding can leave vertices used only by dropped faces: keep the vertex list compact.
  std::vector<int> remap(mesh.vertices.size(), -1);
  std::vector<Vec3> used;
  for (auto& t : mesh.triangles)
    for (int& v : t) {
      if (remap[v] < 0) {
        remap[v] = int(used.size());
        used.push_back(mesh.vertices[v]);
      }
      v = remap[v];
    }
  mesh.vertices = std::move(used);
  ValidateMesh(mesh, path);
  if (report_out) *report_out = report;
  return mesh;
}

void ValidateMesh(const TriangleMesh& mesh, const std::string& name) {
  if (mesh.triangles.empty()) throw Error(name + ": mesh has no triangles");
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    for (double x : mesh.vertices[v])
      if (!std::isfinite(x))
        throw Error(name + ": vertex " + std::to_string(v) + " has a non-finite coordinate " +
                    FormatVec(mesh.vertices[v]));
  const auto n = std::int64_t(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int v : mesh.triangles[t])
      if (v < 0 || v >= n)
        throw Error(name + ": triangle " + std::to_string(t) + " uses vertex " +
                    std::to_string(v) + ", outside [0, " + std::to_string(n) + ")");
}

std::int64_t RemoveDegenerateTriangles(TriangleMesh& mesh) {
  const auto before = mesh.triangles.size();
  std::erase_if(mesh.triangles, [&](const auto& t) { return IsDegenerate(mesh, t); });
  return std::int64_t(before - mesh.triangles.size());
}

void WritePly(const std::string& path, const TriangleMesh& mesh, PlyPrecision precision) {
  ValidateMesh(mesh, path);
  const bool f64 = precision == PlyPrecision::kFloat64;
  const char* type = f64 ? "double" : "float";
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by quijibo\n";
  header += "element vertex " + std::to_string(mesh.vertices.size()) + "\n";
  for (const char* axis : {"x", "y", "z"}) header += std::string("property ") + type + " " + axis + "\n";
  header += "element face " + std::to_string(mesh.triangles.size()) + "\n";
  header += "property list uchar int vertex_indices\nend_header\n";
  const std::size_t vertex_bytes = 3 * (f64 ? sizeof(double) : sizeof(float));
  const std::size_t face_bytes = 1 + 3 * sizeof(std::int32_t);
  std::string bytes(header.size() + vertex_bytes * mesh.vertices.size() +
                        face_bytes * mesh.triangles.size(),
                    '\0');
  std::memcpy(bytes.data(), header.data(), header.size());
  char* out = bytes.data() + header.size();
  for (const Vec3& p : mesh.vertices)
    for (double x : p) {
      if (f64)
        Put(out, x);
      else
        Put(out, float(x));
    }
  for (const auto& t : mesh.triangles) {
    Put(out, std::uint8_t(3));
    for (int v : t) Put(out, std::int32_t(v));
  }
  WriteFileAtomically(path, bytes);
}

void WriteObj(const std::string& path, const TriangleMesh& mesh) {
  ValidateMesh(mesh, path);
  std::string text = "# written by quijibo\n";
  text.reserve(text.size() + 60 * mesh.vertices.size() + 30 * mesh.triangles.size());
  char buf[32];
  for (const Vec3& p : mesh.vertices) {
    text += 'v';
    for (double x : p) {
      text += ' ';
      text.append(buf, std::to_chars(buf, buf + sizeof buf, x).ptr);
    }
    text += '\n';
  }
  for (const auto& t : mesh.triangles) {
    text += 'f';
    for (int v : t) {
      text += ' ';
      text.append(buf, std::to_chars(buf, buf + sizeof buf, v + 1).ptr);
    }
    text += '\n';
  }
  WriteFileAtomically(path, text);
}

BoundingBox ComputeBoundingBox(const TriangleMesh& mesh) {
  BoundingBox box;
  if (mesh.vertices.empty()) return box;
  box.min = box.max = mesh.vertices[0];
  for (const Vec3& p : mesh.vertices)
    for (int a = 0; a < 3; ++a) {
      box.min[a] = std::min(box.min[a], p[a]);
      box.max[a] = std::max(box.max[a], p[a]);
    }
  return box;
}

MeshTopology AnalyzeTopology(const TriangleMesh& mesh) {
  MeshTopology topo;
  // One record per directed edge: key = (low vertex, high vertex), bit 0 = direction.
  std::vector<std::uint64_t> edges;
  edges.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      const auto a = std::uint64_t(t[c]), b = std::uint64_t(t[(c + 1) % 3]);
      const std::uint64_t lo = std::min(a, b), hi = std::max(a, b);
      edges.push_back((lo << 33) | (hi << 1) | (a < b ? 1u : 0u));
    }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    int forward = 0;
    while (j < edges.size() && (edges[j] >> 1) == (edges[i] >> 1)) forward += int(edges[j++] & 1);
    const auto uses = std::int64_t(j - i);
    ++topo.edges;
    if (uses == 1) ++topo.boundary_edges;
    if (uses > 2) ++topo.non_manifold_edges;
    if (uses == 2 && forward != 1) ++topo.misoriented_edges;
    i = j;
  }
  const BoundingBox box = ComputeBoundingBox(mesh);
  Vec3 c;
  for (int a = 0; a < 3; ++a) c[a] = 0.5 * (box.min[a] + box.max[a]);
  double six_v = 0.0;
  for (const auto& t : mesh.triangles) {
    const Vec3 a = Sub(mesh.vertices[t[0]], c), b = Sub(mesh.vertices[t[1]], c),
               d = Sub(mesh.vertices[t[2]], c);
    const Vec3 bxd = Cross(b, d);
    six_v += a[0] * bxd[0] + a[1] * bxd[1] + a[2] * bxd[2];
  }
  topo.signed_volume = six_v / 6.0;
  return topo;
}

void FlipOrientation(TriangleMesh& mesh) {
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
}

}  // namespace quijibo::mesh
