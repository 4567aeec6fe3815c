#include "mesh/mesh_stream.h"

#include <fcntl.h>
#include <omp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <unordered_set>

#include "util/error.h"
#include "util/progress.h"

namespace quijibo::mesh {

// The stream's helpers (a named namespace: MeshStreamWriter::State holds them).
namespace streaming {

static_assert(std::endian::native == std::endian::little, "the stream writes native little-endian bytes");

std::string Folder(const std::string& path) {
  const std::string d = std::filesystem::path(path).parent_path().string();
  return d.empty() ? "." : d;
}

// A file with no name (O_TMPFILE, or a name removed at once), so nothing is left behind however the
// process ends; buffered appends, read back in chunks.
class Scratch {
 public:
  Scratch(const std::string& folder, const std::string& what) : what_(what) {
    fd_ = ::open(folder.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
    if (fd_ < 0) {  // file systems without O_TMPFILE
      std::string name = folder + "/.quijibo-stream-XXXXXX";
      fd_ = ::mkostemp(name.data(), O_CLOEXEC);
      if (fd_ >= 0) ::unlink(name.c_str());
    }
    if (fd_ < 0) throw Error(what_ + ": cannot create a scratch file in " + folder + ": " + std::strerror(errno));
    buffer_.reserve(kBuffer);
  }
  ~Scratch() {
    if (fd_ >= 0) ::close(fd_);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  template <class T>
  void put(const T& v) {
    const char* p = reinterpret_cast<const char*>(&v);
    buffer_.insert(buffer_.end(), p, p + sizeof(T));
    if (buffer_.size() >= kBuffer) flush();
  }
  void append(const char* p, std::size_t n) {
    buffer_.insert(buffer_.end(), p, p + n);
    if (buffer_.size() >= kBuffer) flush();
  }
  void flush() {
    std::size_t done = 0;
    while (done < buffer_.size()) {
      const ssize_t n = ::write(fd_, buffer_.data() + done, buffer_.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) throw Error(what_ + ": cannot write: " + std::strerror(n < 0 ? errno : ENOSPC));
      done += std::size_t(n);
    }
    size_ += buffer_.size();
    buffer_.clear();
  }
  std::uint64_t size() const { return size_ + buffer_.size(); }
  // Calls f(bytes, n) on consecutive chunks of the flushed content, each a multiple of `record`.
  template <class F>
  void read_all(std::size_t record, F&& f) {
    flush();
    std::vector<char> chunk((kBuffer / record) * record);
    std::uint64_t at = 0;
    while (at < size_) {
      const std::size_t want = std::size_t(std::min<std::uint64_t>(chunk.size(), size_ - at));
      std::size_t got = 0;
      while (got < want) {
        const ssize_t n = ::pread(fd_, chunk.data() + got, want - got, off_t(at + got));
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) throw Error(what_ + ": cannot read a scratch file back: " + std::strerror(n < 0 ? errno : EIO));
        got += std::size_t(n);
      }
      f(chunk.data(), want);
      at += want;
    }
  }
  int fd() const { return fd_; }

 private:
  static constexpr std::size_t kBuffer = 1 << 20;
  std::string what_;
  int fd_ = -1;
  std::vector<char> buffer_;
  std::uint64_t size_ = 0;
};

// Union-find over sorted 64-bit keys (edge ids) of the front: 16 bytes per key, no hashing.
struct SortedUnionFind {
  std::vector<std::int64_t> key;
  std::vector<std::size_t> parent;
  explicit SortedUnionFind(std::vector<std::int64_t> keys) : key(std::move(keys)) {
    std::sort(key.begin(), key.end());
    key.erase(std::unique(key.begin(), key.end()), key.end());
    key.shrink_to_fit();
    parent.resize(key.size());
    for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = i;
  }
  std::size_t at(std::int64_t k) const { return std::size_t(std::lower_bound(key.begin(), key.end(), k) - key.begin()); }
  bool has(std::int64_t k) const { return std::binary_search(key.begin(), key.end(), k); }
  std::size_t find(std::size_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a), b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

// A mesh edge (the edge ids of its two vertices, low first) and the triangles counted on it.
struct EdgeCount {
  std::int64_t lo, hi;
  int count;
};

}  // namespace streaming

using namespace streaming;

std::string MeshStreamOptions::Validate() const {
  if (path.empty()) return "streaming: no output file";
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".ply") return "streaming: the mesh must be a .ply (" + path + ")";
  if (index_bits != 0 && index_bits != 64) return "streaming: index bits must be 0 (automatic) or 64";
  return {};
}

// A piece waiting in the front: its vertices get their global index when their plane is complete.
struct HeldPiece {
  std::int64_t bottom_plane = 0, top_plane = 0;  // the z planes its vertices can lie on
  std::vector<std::int64_t> edges;
  std::vector<Vec3> positions;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<std::int64_t> global;  // -1 until numbered
};

struct MeshStreamWriter::State {
  const TilePlan& plan;
  MeshStreamOptions o;
  std::int64_t nx = 0, nxy = 0, tiles_per_layer = 0;
  std::map<std::size_t, TilePiece> ahead;  // finished before an earlier tile
  std::size_t next = 0;                    // the next piece in plan order
  std::deque<HeldPiece> front;
  std::int64_t numbered_below = 0;         // planes z < this are numbered
  std::uint64_t vertices = 0, triangles = 0;
  std::unordered_set<std::int64_t> removed;  // edges of the vertices of specks
  std::vector<std::pair<std::int64_t, std::int64_t>> carry;  // (live vertex, its component's label)
  std::vector<EdgeCount> pairs;  // mesh edges that tiles still to be written may touch
  std::int64_t specks = 0, components = 0, open = 0, open_inside = 0, non_manifold = 0;
  std::int64_t nodes = 0, bisection = 0, non_finite = 0, blocks_active = 0;
  MeshStreamReport report;
  Scratch vertex_file, face_file;
  bool finished = false;

  State(const TilePlan& p, MeshStreamOptions opts)
      : plan(p), o(std::move(opts)), vertex_file(Folder(o.path), o.path), face_file(Folder(o.path), o.path) {
    nx = plan.lattice.cells[0] + 1;
    nxy = nx * (plan.lattice.cells[1] + 1);
    tiles_per_layer = plan.tiles[0] * plan.tiles[1];
  }
  std::int64_t plane(std::int64_t edge) const { return edge / 3 / nxy; }
  std::int64_t layer_of(std::size_t index) const { return plan.tile_ids[index] / tiles_per_layer; }

  void absorb(TilePiece&& p) {
    nodes += p.nodes_evaluated;
    bisection += p.bisection_evaluations;
    non_finite += p.non_finite_values;
    blocks_active += p.blocks_active;
    report.band_samples += std::int64_t(p.band_nodes.size());
    if (o.band) o.band(p);
    HeldPiece h;
    h.bottom_plane = p.tile / tiles_per_layer * plan.options.tile_cells;
    h.top_plane = std::min<std::int64_t>(h.bottom_plane + plan.options.tile_cells, plan.lattice.cells[2]);
    h.edges = std::move(p.vertex_edges);
    h.positions = std::move(p.vertex_positions);
    h.triangles = std::move(p.triangles);
    h.global.assign(h.edges.size(), -1);
    if (!h.triangles.empty()) front.push_back(std::move(h));
  }

  void note_front() {
    std::int64_t tris = 0;
    for (const auto& h : front) tris += std::int64_t(h.triangles.size());
    for (const auto& [i, p] : ahead) tris += std::int64_t(p.triangles.size());
    report.peak_front_tiles = std::max(report.peak_front_tiles, std::int64_t(front.size() + ahead.size()));
    report.peak_front_triangles = std::max(report.peak_front_triangles, tris);
  }

  // One-node specks whose lowest vertex lies on a plane in [lo, hi): every cell around their node is
  // in the front then, and every triangle touching them (RemoveNodeSpecks' test on the front).
  void decide_specks(std::int64_t lo, std::int64_t hi) {
    std::vector<std::int64_t> keys;
    for (const auto& h : front)
      for (const auto& t : h.triangles)
        if (!removed.count(h.edges[std::size_t(t[0])]))
          for (int c = 0; c < 3; ++c) keys.push_back(h.edges[std::size_t(t[std::size_t(c)])]);
    SortedUnionFind uf(std::move(keys));
    const std::size_t n = uf.parent.size();
    std::vector<int> verts(n, 0), tris(n, 0);
    for (const auto& h : front)
      for (const auto& t : h.triangles)
        if (!removed.count(h.edges[std::size_t(t[0])])) {
          const std::size_t a = uf.at(h.edges[std::size_t(t[0])]);
          uf.unite(a, uf.at(h.edges[std::size_t(t[1])]));
          uf.unite(a, uf.at(h.edges[std::size_t(t[2])]));
        }
    for (std::size_t v = 0; v < n; ++v) ++verts[uf.find(v)];
    for (const auto& h : front)
      for (const auto& t : h.triangles)
        if (!removed.count(h.edges[std::size_t(t[0])])) ++tris[uf.find(uf.at(h.edges[std::size_t(t[0])]))];
    const std::int64_t step[3] = {1, nx, nxy};
    std::vector<std::pair<std::size_t, std::int64_t>> ends;  // (component, edge end node)
    for (std::size_t v = 0; v < n; ++v) {
      const std::size_t r = uf.find(v);
      if (verts[r] == 6 && tris[r] == 8) {
        const std::int64_t node = uf.key[v] / 3;
        ends.push_back({r, node});
        ends.push_back({r, node + step[uf.key[v] % 3]});
      }
    }
    std::sort(ends.begin(), ends.end());
    std::vector<char> speck(n, 0);
    for (std::size_t i = 0; i + 5 < ends.size(); ++i)
      if (ends[i] == ends[i + 5] && !speck[ends[i].first]) {
        const std::int64_t k = ends[i].second / nxy;  // the node's plane; its lowest vertex is on k - 1
        if (k - 1 < lo || k - 1 >= hi) continue;
        speck[ends[i].first] = 1;
        ++specks;
      }
    for (std::size_t v = 0; v < n; ++v)
      if (speck[uf.find(v)]) removed.insert(uf.key[v]);
  }

  // Numbers the vertices on planes [numbered_below, below), writes them and every triangle whose
  // vertices are all numbered, and counts what the written triangles settle.
  void flush(std::int64_t below) {
    if (below <= numbered_below) return;
    ++report.flushes;
    const std::int64_t lo = numbered_below;
    if (plan.options.remove_specks) decide_specks(lo, below);
    struct Ref {
      std::int64_t edge;
      std::uint32_t piece, v;
    };
    std::vector<Ref> refs;
    for (std::size_t h = 0; h < front.size(); ++h)
      for (std::size_t v = 0; v < front[h].edges.size(); ++v) {
        const std::int64_t e = front[h].edges[v], p = plane(e);
        if (p >= lo && p < below && !removed.count(e)) refs.push_back({e, std::uint32_t(h), std::uint32_t(v)});
      }
    std::sort(refs.begin(), refs.end(), [](const Ref& a, const Ref& b) {
      return a.edge < b.edge || (a.edge == b.edge && a.piece < b.piece);
    });
    const bool f64 = o.precision == PlyPrecision::kFloat64;
    for (std::size_t i = 0; i < refs.size(); ++i) {
      HeldPiece& h = front[refs[i].piece];
      if (i == 0 || refs[i].edge != refs[i - 1].edge) {
        Vec3 x = h.positions[refs[i].v];
        if (o.transform) x = o.transform(x);
        for (double c : x) {
          if (!std::isfinite(c)) throw Error(o.path + ": a vertex has a non-finite coordinate");
          if (f64) vertex_file.put(c);
          else vertex_file.put(float(c));
        }
        ++vertices;
      }
      h.global[refs[i].v] = std::int64_t(vertices - 1);
    }
    numbered_below = below;
    // Triangles in tile order, of the pieces whose planes are all numbered; a union-find over their
    // vertices and the labels carried from the last step.
    std::size_t ready = 0;
    while (ready < front.size() && front[ready].top_plane < below) ++ready;
    std::vector<std::int64_t> keys;
    for (const auto& [v, label] : carry) keys.push_back(v), keys.push_back(label);
    for (std::size_t i = 0; i < ready; ++i)
      for (const auto& t : front[i].triangles)
        if (!removed.count(front[i].edges[std::size_t(t[0])]))
          for (int c = 0; c < 3; ++c) keys.push_back(front[i].edges[std::size_t(t[std::size_t(c)])]);
    SortedUnionFind uf(std::move(keys));
    for (const auto& [v, label] : carry) uf.unite(uf.at(v), uf.at(label));
    std::vector<EdgeCount> counts;
    counts.swap(pairs);
    for (; ready > 0; --ready) {
      HeldPiece& h = front.front();
      for (const auto& t : h.triangles) {
        if (removed.count(h.edges[std::size_t(t[0])])) continue;
        std::array<std::int64_t, 3> e;
        for (int c = 0; c < 3; ++c) {
          e[std::size_t(c)] = h.edges[std::size_t(t[std::size_t(c)])];
          const std::int64_t g = h.global[std::size_t(t[std::size_t(c)])];
          if (g < 0) throw Error("meshing: stream: a triangle's vertex was not numbered (a bug)");
          face_file.put(std::uint64_t(g));
        }
        ++triangles;
        const std::size_t a = uf.at(e[0]);
        uf.unite(a, uf.at(e[1]));
        uf.unite(a, uf.at(e[2]));
        for (int c = 0; c < 3; ++c) {
          const std::int64_t u = e[std::size_t(c)], w = e[std::size_t((c + 1) % 3)];
          counts.push_back({std::min(u, w), std::max(u, w), 1});
        }
      }
      front.pop_front();
    }
    // Components: those with no vertex left in the front are complete; the others carry a label.
    std::vector<std::int64_t> live;
    for (const auto& h : front)
      for (std::int64_t e : h.edges)
        if (uf.has(e)) live.push_back(e);
    std::sort(live.begin(), live.end());
    live.erase(std::unique(live.begin(), live.end()), live.end());
    std::vector<char> root_live(uf.parent.size(), 0);
    for (std::int64_t e : live) root_live[uf.find(uf.at(e))] = 1;
    for (std::size_t v = 0; v < uf.parent.size(); ++v)
      if (uf.find(v) == v && !root_live[v]) ++components;
    carry.clear();
    for (std::int64_t e : live) carry.push_back({e, uf.key[uf.find(uf.at(e))]});
    // Mesh edges with a vertex below every tile still to be written can get no more triangles.
    const std::int64_t floor = !front.empty()                ? front.front().bottom_plane
                               : next < plan.tile_ids.size() ? layer_of(next) * plan.options.tile_cells
                                                             : std::numeric_limits<std::int64_t>::max();
    std::sort(counts.begin(), counts.end(),
              [](const EdgeCount& x, const EdgeCount& y) { return x.lo < y.lo || (x.lo == y.lo && x.hi < y.hi); });
    for (std::size_t i = 0; i < counts.size();) {
      EdgeCount sum = counts[i];
      std::size_t j = i + 1;
      for (; j < counts.size() && counts[j].lo == sum.lo && counts[j].hi == sum.hi; ++j) sum.count += counts[j].count;
      if (std::min(plane(sum.lo), plane(sum.hi)) < floor) settle(sum.lo, sum.hi, sum.count);
      else pairs.push_back(sum);
      i = j;
    }
    for (auto it = removed.begin(); it != removed.end();)
      it = plane(*it) < floor ? removed.erase(it) : std::next(it);
  }

  // As AnalyzeLatticeMesh: an edge used once is open, inside unless both ends lie on one box face.
  void settle(std::int64_t lo, std::int64_t hi, int count) {
    if (count > 2) ++non_manifold;
    if (count != 1) return;
    ++open;
    auto faces_of = [&](std::int64_t edge) {
      const std::int64_t node = edge / 3, axis = edge % 3;
      const std::int64_t ijk[3] = {node % nx, (node / nx) % (nxy / nx), node / nxy};
      unsigned bits = 0;
      for (int a = 0; a < 3; ++a) {
        if (a == axis) continue;
        const std::int64_t i = ijk[a], n = plan.lattice.cells[std::size_t(a)];
        bits |= (i == 0 ? 1u : 0u) << (2 * a) | (i == n ? 1u : 0u) << (2 * a + 1);
      }
      return bits;
    };
    if (!(faces_of(lo) & faces_of(hi))) ++open_inside;
  }
};

std::string PlyIndexType(std::uint64_t vertices, int index_bits) {
  if (index_bits == 64 || vertices > (std::uint64_t(1) << 32)) return "uint64";
  if (vertices > (std::uint64_t(1) << 31)) return "uint";
  return "int";
}

MeshStreamWriter::MeshStreamWriter(const TilePlan& plan, MeshStreamOptions options) {
  if (auto why = options.Validate(); !why.empty()) throw Error(why);
  s_ = std::make_unique<State>(plan, std::move(options));
}

MeshStreamWriter::~MeshStreamWriter() = default;

void MeshStreamWriter::Add(std::size_t index, TilePiece piece) {
  State& s = *s_;
  if (s.finished) throw Error("meshing: stream: a piece after Finish");
  if (index >= s.plan.tile_ids.size() || index < s.next || s.ahead.count(index) ||
      piece.tile != s.plan.tile_ids[index])
    throw Error("meshing: stream: an unknown, repeated or misplaced piece (tile index " + std::to_string(index) + ")");
  s.ahead.emplace(index, std::move(piece));
  s.note_front();
  bool moved = false;
  while (!s.ahead.empty() && s.ahead.begin()->first == s.next) {
    s.absorb(std::move(s.ahead.begin()->second));
    s.ahead.erase(s.ahead.begin());
    ++s.next;
    moved = true;
  }
  if (!moved) return;
  s.note_front();
  // Planes below the next tile's layer are complete; specks need one plane more (flush's comment).
  if (s.next < s.plan.tile_ids.size())
    s.flush(s.layer_of(s.next) * s.plan.options.tile_cells - 1);
}

MeshStreamReport MeshStreamWriter::Finish(MeshingSummary* summary) {
  State& s = *s_;
  if (s.finished) throw Error("meshing: stream: Finish twice");
  if (s.next != s.plan.tile_ids.size())
    throw Error("meshing: stream: " + std::to_string(s.plan.tile_ids.size() - s.next) + " tiles missing at the end");
  s.flush(std::numeric_limits<std::int64_t>::max());
  for (const EdgeCount& e : s.pairs) s.settle(e.lo, e.hi, e.count);
  s.pairs.clear();
  s.finished = true;
  MeshStreamReport& r = s.report;
  r.non_manifold_edges = s.non_manifold;
  r.index_type = PlyIndexType(s.vertices, s.o.index_bits);
  if (summary) {
    MeshingSummary& m = *summary;
    m.nodes_evaluated = s.plan.search_evaluations + s.nodes;
    m.bisection_evaluations = s.bisection;
    m.non_finite_values = s.plan.search_non_finite + s.non_finite;
    m.search_evaluations = s.plan.search_evaluations;
    m.tiles_total = s.plan.tiles_total();
    m.tiles_meshed = std::int64_t(s.plan.tile_ids.size());
    m.blocks_total = s.plan.blocks_total;
    m.blocks_active = s.blocks_active;
    m.specks_removed = s.specks;
    m.speck_removal = s.plan.options.remove_specks;
    m.follow_evaluations = s.plan.follow_evaluations;
    m.blocks_followed = s.plan.blocks_followed;
    m.open_edges = s.open;
    m.open_edges_inside = s.open_inside;
    m.components = s.components;
    m.vertices = std::int64_t(s.vertices);
    m.triangles = std::int64_t(s.triangles);
    m.cells = s.plan.lattice.cells;
    m.search_stride = s.plan.search_stride;
    m.spacing = s.plan.lattice.spacing;
  }
  if (s.triangles == 0) return r;  // no mesh, no file (as WritePly refuses an empty mesh)

  // The PLY: WritePly's header, the vertices, the faces with the index type chosen now.
  const bool f64 = s.o.precision == PlyPrecision::kFloat64;
  std::string header = "ply\nformat binary_little_endian 1.0\ncomment written by quijibo\n";
  header += "element vertex " + std::to_string(s.vertices) + "\n";
  for (const char* axis : {"x", "y", "z"}) header += std::string("property ") + (f64 ? "double" : "float") + " " + axis + "\n";
  header += "element face " + std::to_string(s.triangles) + "\n";
  header += "property list uchar " + r.index_type + " vertex_indices\nend_header\n";
  const std::string& path = s.o.path;
  const std::string folder = Folder(path);
  Scratch out(folder, path);
  out.append(header.data(), header.size());
  s.vertex_file.read_all(1, [&](const char* p, std::size_t n) { out.append(p, n); });
  const int width = r.index_type == "uint64" ? 8 : 4;
  s.face_file.read_all(3 * sizeof(std::uint64_t), [&](const char* p, std::size_t n) {
    for (std::size_t at = 0; at < n; at += 3 * sizeof(std::uint64_t)) {
      out.put(std::uint8_t(3));
      for (int c = 0; c < 3; ++c) {
        std::uint64_t g;
        std::memcpy(&g, p + at + std::size_t(c) * sizeof g, sizeof g);
        if (width == 8) out.put(g);
        else out.put(std::uint32_t(g));
      }
    }
  });
  out.flush();
  if (::fsync(out.fd()) != 0) throw Error(path + ": cannot write: " + std::strerror(errno));
  // Give the unnamed file a temporary name in the folder, then rename it into place.
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  ::unlink(tmp.c_str());
  const std::string proc = "/proc/self/fd/" + std::to_string(out.fd());
  if (::linkat(AT_FDCWD, proc.c_str(), AT_FDCWD, tmp.c_str(), AT_SYMLINK_FOLLOW) != 0) {
    // No /proc or a named scratch (already unlinked): copy through a named file.
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(path + ": cannot write: " + std::strerror(errno));
    std::vector<char> chunk(1 << 20);
    off_t at = 0;
    for (;;) {
      const ssize_t n = ::pread(out.fd(), chunk.data(), chunk.size(), at);
      if (n < 0 && errno == EINTR) continue;
      if (n == 0) break;
      if (n < 0 || ::write(fd, chunk.data(), std::size_t(n)) != n) {
        const int err = errno;
        ::close(fd);
        ::unlink(tmp.c_str());
        throw Error(path + ": cannot write: " + std::strerror(err));
      }
      at += n;
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
      const int err = errno;
      ::unlink(tmp.c_str());
      throw Error(path + ": cannot write: " + std::strerror(err));
    }
  } else {  // the permissions a new file gets (O_TMPFILE made it 0600)
    const mode_t mask = ::umask(0);
    ::umask(mask);
    ::fchmod(out.fd(), 0644 & ~mask);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp.c_str());
    throw Error(path + ": cannot write: " + std::strerror(err));
  }
  r.bytes = std::int64_t(out.size());
  return r;
}

MeshStreamReport MeshFieldStreamed(const BatchField& field, const MeshingOptions& o, const MeshStreamOptions& stream,
                                   MeshingSummary* summary) {
  const auto t0 = std::chrono::steady_clock::now();
  const TilePlan plan = PlanTiles(field, o);
  MeshStreamWriter writer(plan, stream);
  const std::int64_t n = std::int64_t(plan.tile_ids.size());
  Progress progress("mesh: tiles", double(n), !o.show_progress);
  std::int64_t done = 0;
  std::exception_ptr error;
  bool failed = false;
  // Dynamic scheduling hands the tiles out in plan order, so the pieces ahead of the oldest
  // unfinished tile are at most one per thread.
#pragma omp parallel for schedule(dynamic)
  for (std::int64_t ti = 0; ti < n; ++ti) {
    bool skip;
#pragma omp atomic read
    skip = failed;
    if (skip) continue;
    try {
      TilePiece piece = MeshTilePiece(field, plan, std::size_t(ti), stream.band != nullptr);
#pragma omp critical(quijibo_mesh_stream)
      {
        try {
          if (!failed) {
            writer.Add(std::size_t(ti), std::move(piece));
            ++done;
            progress.update(double(done), std::to_string(done) + " of " + std::to_string(n) + " tiles");
          }
        } catch (...) {
          if (!error) error = std::current_exception();
#pragma omp atomic write
          failed = true;
        }
      }
    } catch (...) {
#pragma omp critical(quijibo_mesh_stream)
      {
        if (!error) error = std::current_exception();
#pragma omp atomic write
        failed = true;
      }
    }
  }
  progress.finish();
  if (error) std::rethrow_exception(error);
  MeshStreamReport r = writer.Finish(summary);
  if (summary) summary->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

IndexedMesh64 ReadBinaryPly(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open");
  auto fail = [&](const std::string& why) { return Error(path + ": " + why); };
  std::string line;
  std::getline(in, line);
  if (line != "ply") throw fail("not a PLY file");
  std::uint64_t nv = 0, nf = 0;
  int coord = 0, index = 0;
  bool face = false;
  std::string index_type;
  while (std::getline(in, line) && line != "end_header") {
    if (line.rfind("format ", 0) == 0 && line != "format binary_little_endian 1.0")
      throw fail("expected binary_little_endian, found \"" + line + "\"");
    if (line.rfind("element vertex ", 0) == 0) nv = std::stoull(line.substr(15)), face = false;
    else if (line.rfind("element face ", 0) == 0) nf = std::stoull(line.substr(13)), face = true;
    else if (line.rfind("property list uchar ", 0) == 0 && face) {
      index_type = line.substr(20, line.find(' ', 20) - 20);
      index = index_type == "int" || index_type == "uint" ? 4 : index_type == "int64" || index_type == "uint64" ? 8 : 0;
      if (!index) throw fail("unsupported face index type \"" + index_type + "\"");
    } else if (line.rfind("property ", 0) == 0 && !face) {
      const int c = line.rfind("property float ", 0) == 0 ? 4 : line.rfind("property double ", 0) == 0 ? 8 : 0;
      if (!c || (coord && c != coord)) throw fail("expected float or double x y z, found \"" + line + "\"");
      coord = c;
    }
  }
  if (line != "end_header" || !coord || !index) throw fail("incomplete header");
  const auto size = std::filesystem::file_size(path);
  if (nv * 3 * std::uint64_t(coord) + nf * (1 + 3 * std::uint64_t(index)) > size) throw fail("truncated");
  IndexedMesh64 m;
  m.index_type = index_type;
  m.vertices.resize(nv);
  for (auto& v : m.vertices)
    for (double& x : v) {
      if (coord == 8) in.read(reinterpret_cast<char*>(&x), 8);
      else {
        float f;
        in.read(reinterpret_cast<char*>(&f), 4);
        x = f;
      }
    }
  m.triangles.resize(nf);
  for (auto& t : m.triangles) {
    std::uint8_t k = 0;
    in.read(reinterpret_cast<char*>(&k), 1);
    if (k != 3) throw fail("a face that is not a triangle");
    for (auto& i : t) {
      i = 0;
      in.read(reinterpret_cast<char*>(&i), index);
      if (index == 4 && (index_type == "int") && (i >> 31)) throw fail("a negative index");
      if (i >= nv) throw fail("an index out of range");
    }
  }
  if (!in) throw fail("truncated");
  return m;
}

}  // namespace quijibo::mesh
