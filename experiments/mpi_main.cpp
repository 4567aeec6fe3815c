// quijibo-mpi: `quijibo mesh` over MPI ranks, and parameter sweeps of `quijibo` commands (docs/mpi.md).
//
// mesh: every rank builds the field; the sparse search's lattice is split evenly over the ranks
// (Allgatherv, so every rank holds the same tile plan); then rank 0 hands out batches of tiles on demand
// (a work queue: tiles differ wildly in surface), meshes batches itself on a second thread, receives the
// pieces (vertices keyed by global edge id) as they finish, welds them in tile order and writes. The
// result does not depend on which rank meshed which tile: it is the single-process mesh, bit for bit.
//
// sweep: rank 0 hands out jobs (argument vectors of `quijibo`) one at a time; each rank runs its job as
// a child process in its own folder; rank 0 writes index.json.
#include <mpi.h>
#include <omp.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <map>
#include <thread>

#include "experiments/cli.h"
#include "mesh/julia_field.h"
#include "mesh/marching_cubes.h"
#include "quijibo/error.h"
#include "quijibo/progress.h"

extern char** environ;

namespace quijibo::mpi {

using nlohmann::json;

namespace {

int Rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
int Size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}
double Now() { return MPI_Wtime(); }
void Nap() { std::this_thread::sleep_for(std::chrono::microseconds(200)); }  // not a busy wait

constexpr int kTagWork = 11, kTagResult = 12;

// ---------------------------------------------------------------------------------------------
// Byte buffers.

struct Writer {
  std::vector<char> bytes;
  template <class T>
  void pod(const T& v) {
    const char* p = reinterpret_cast<const char*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  template <class T>
  void vec(const std::vector<T>& v) {
    pod(std::uint64_t(v.size()));
    const char* p = reinterpret_cast<const char*>(v.data());
    bytes.insert(bytes.end(), p, p + sizeof(T) * v.size());
  }
};

struct Reader {
  const std::vector<char>& bytes;
  std::size_t at = 0;
  template <class T>
  T pod() {
    if (at + sizeof(T) > bytes.size()) throw Error("quijibo-mpi: truncated message");
    T v;
    std::memcpy(&v, bytes.data() + at, sizeof(T));
    at += sizeof(T);
    return v;
  }
  template <class T>
  void vec(std::vector<T>& v) {
    const auto n = pod<std::uint64_t>();
    if (at + n * sizeof(T) > bytes.size()) throw Error("quijibo-mpi: truncated message");
    v.resize(n);
    if (n) std::memcpy(v.data(), bytes.data() + at, n * sizeof(T));
    at += n * sizeof(T);
  }
};

void PackPiece(Writer& w, std::int64_t index, const TilePiece& p) {
  w.pod(index);
  w.pod(p.tile);
  w.vec(p.vertex_edges);
  w.vec(p.vertex_positions);
  w.vec(p.triangles);
  w.vec(p.band_nodes);
  w.vec(p.band_values);
  w.pod(p.nodes_evaluated);
  w.pod(p.bisection_evaluations);
  w.pod(p.non_finite_values);
  w.pod(p.blocks_active);
}

std::int64_t UnpackPiece(Reader& r, TilePiece& p) {
  const auto index = r.pod<std::int64_t>();
  p.tile = r.pod<std::int64_t>();
  r.vec(p.vertex_edges);
  r.vec(p.vertex_positions);
  r.vec(p.triangles);
  r.vec(p.band_nodes);
  r.vec(p.band_values);
  p.nodes_evaluated = r.pod<std::int64_t>();
  p.bisection_evaluations = r.pod<std::int64_t>();
  p.non_finite_values = r.pod<std::int64_t>();
  p.blocks_active = r.pod<std::int64_t>();
  return index;
}

void SendBytes(const std::vector<char>& b, int to, int tag) {
  if (b.size() > std::size_t(INT_MAX)) throw Error("quijibo-mpi: a message over 2 GB (use smaller --tile)");
  MPI_Send(b.data(), int(b.size()), MPI_BYTE, to, tag, MPI_COMM_WORLD);
}

std::vector<char> ReceiveBytes(const MPI_Status& probed) {
  int count = 0;
  MPI_Get_count(&probed, MPI_BYTE, &count);
  std::vector<char> b(std::size_t(std::max(count, 0)));
  MPI_Recv(b.data(), count, MPI_BYTE, probed.MPI_SOURCE, probed.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return b;
}

// ---------------------------------------------------------------------------------------------
// mesh

// The sparse search's lattice split evenly over the ranks (contiguous slices), gathered everywhere.
PointsEvaluator SpreadSearch(const BatchField& field) {
  return [&field](const std::vector<Vec3>& points, std::vector<double>& values) {
    const int P = Size(), r = Rank();
    const std::int64_t n = std::int64_t(points.size());
    if (n > INT_MAX) throw Error("quijibo-mpi: search level over 2^31 points");
    std::vector<int> counts(static_cast<std::size_t>(P)), displs(static_cast<std::size_t>(P));
    for (int p = 0; p < P; ++p) {
      const std::int64_t b = n * p / P, e = n * (p + 1) / P;
      displs[std::size_t(p)] = int(b);
      counts[std::size_t(p)] = int(e - b);
    }
    const std::int64_t b = displs[std::size_t(r)], m = counts[std::size_t(r)];
    std::vector<double> mine(std::size_t(std::max<std::int64_t>(m, 1)));
    const std::int64_t chunk = 2048, chunks = (m + chunk - 1) / chunk;
#pragma omp parallel for schedule(dynamic)
    for (std::int64_t c = 0; c < chunks; ++c) {
      const std::int64_t cb = c * chunk, ce = std::min(m, cb + chunk);
      field.evaluate(points.data() + b + cb, std::size_t(ce - cb), mine.data() + cb);
    }
    values.resize(points.size());
    MPI_Allgatherv(mine.data(), int(m), MPI_DOUBLE, values.data(), counts.data(), displs.data(), MPI_DOUBLE,
                   MPI_COMM_WORLD);
  };
}

// Tiles per batch: at least one per thread of the asking rank, fewer as the queue drains.
std::int64_t BatchSize(std::int64_t remaining, int threads, int ranks) {
  const std::int64_t want = std::max<std::int64_t>(threads, std::min<std::int64_t>(4 * threads, remaining / (4 * ranks)));
  return std::min(remaining, want);
}

std::vector<std::pair<std::int64_t, TilePiece>> MeshBatch(const BatchField& field, const TilePlan& plan,
                                                          const std::vector<std::int64_t>& batch, bool want_band) {
  std::vector<std::pair<std::int64_t, TilePiece>> out(batch.size());
#pragma omp parallel for schedule(dynamic)
  for (std::int64_t i = 0; i < std::int64_t(batch.size()); ++i) {
    out[std::size_t(i)].first = batch[std::size_t(i)];
    out[std::size_t(i)].second = MeshTilePiece(field, plan, std::size_t(batch[std::size_t(i)]), want_band);
  }
  return out;
}

void Worker(const BatchField& field, const TilePlan& plan, bool want_band) {
  const int threads = omp_get_max_threads();
  Writer w;
  w.pod(std::int32_t(threads));
  w.pod(std::int64_t(0));
  for (;;) {
    SendBytes(w.bytes, 0, kTagResult);
    MPI_Status st;
    MPI_Probe(0, kTagWork, MPI_COMM_WORLD, &st);
    int count = 0;
    MPI_Get_count(&st, MPI_INT64_T, &count);
    std::vector<std::int64_t> batch(std::size_t(std::max(count, 0)));
    MPI_Recv(batch.data(), count, MPI_INT64_T, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (batch.empty()) return;
    const auto pieces = MeshBatch(field, plan, batch, want_band);
    w.bytes.clear();
    w.pod(std::int32_t(threads));
    w.pod(std::int64_t(pieces.size()));
    for (const auto& [index, piece] : pieces) PackPiece(w, index, piece);
  }
}

struct CoordinatorReport {
  std::vector<std::int64_t> tiles_by_rank;
  std::int64_t bytes_received = 0;
};

// Rank 0: the work queue. Its own batches run on a second thread (MPI stays on this one).
std::vector<TilePiece> Coordinate(const BatchField& field, const TilePlan& plan, bool want_band, bool progress_on,
                                  CoordinatorReport& report) {
  const int P = Size();
  const std::int64_t n = std::int64_t(plan.tile_ids.size());
  std::vector<TilePiece> pieces(static_cast<std::size_t>(n));
  report.tiles_by_rank.assign(std::size_t(P), 0);
  std::int64_t next = 0, received = 0;
  int stopped = 0;
  const int own_threads = omp_get_max_threads();
  std::future<std::vector<std::pair<std::int64_t, TilePiece>>> own;
  Progress progress("mesh: tiles", double(n), !progress_on);
  auto store = [&](std::int64_t index, TilePiece&& piece, int rank) {
    if (index < 0 || index >= n) throw Error("quijibo-mpi: a worker sent an unknown tile");
    pieces[std::size_t(index)] = std::move(piece);
    ++received;
    ++report.tiles_by_rank[std::size_t(rank)];
    progress.update(double(received), std::to_string(received) + " of " + std::to_string(n) + " tiles, " +
                                          std::to_string(P) + " ranks");
  };
  auto take = [&](int threads) {
    const std::int64_t m = BatchSize(n - next, threads, P);
    std::vector<std::int64_t> batch(static_cast<std::size_t>(m));
    for (std::int64_t i = 0; i < m; ++i) batch[std::size_t(i)] = next++;
    return batch;
  };
  while (received < n || stopped < P - 1 || own.valid()) {
    bool busy = false;
    // Our own batch.
    if (own.valid() && own.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      for (auto& [index, piece] : own.get()) store(index, std::move(piece), 0);
      busy = true;
    }
    if (!own.valid() && next < n) {
      own = std::async(std::launch::async, [&field, &plan, want_band, batch = take(own_threads)] {
        return MeshBatch(field, plan, batch, want_band);
      });
      busy = true;
    }
    // Workers: results (or the first request), answered with the next batch or a stop.
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &flag, &st);
    if (flag) {
      const std::vector<char> bytes = ReceiveBytes(st);
      report.bytes_received += std::int64_t(bytes.size());
      Reader r{bytes};
      const int threads = std::max(1, int(r.pod<std::int32_t>()));
      const auto count = r.pod<std::int64_t>();
      for (std::int64_t i = 0; i < count; ++i) {
        TilePiece piece;
        const std::int64_t index = UnpackPiece(r, piece);
        store(index, std::move(piece), st.MPI_SOURCE);
      }
      const std::vector<std::int64_t> batch = take(threads);
      if (batch.empty()) ++stopped;
      MPI_Send(batch.data(), int(batch.size()), MPI_INT64_T, st.MPI_SOURCE, kTagWork, MPI_COMM_WORLD);
      busy = true;
    }
    if (!busy) Nap();
  }
  progress.finish();
  return pieces;
}

bool MpiMesher(const BatchField& field, const MeshingOptions& options, MeshingSummary* summary, FieldBand* band,
               TriangleMesh* mesh, JuliaFieldStats* stats) {
  const int P = Size(), rank = Rank();
  const double t0 = Now();
  const TilePlan plan = PlanTiles(field, options, P > 1 ? SpreadSearch(field) : PointsEvaluator{});
  const double t_plan = Now();
  const bool want_band = band != nullptr;
  std::vector<TilePiece> pieces;
  CoordinatorReport report;
  if (rank == 0) pieces = Coordinate(field, plan, want_band, options.show_progress, report);
  else Worker(field, plan, want_band);
  const double t_mesh = Now();
  // The field's counters, summed on rank 0.
  std::int64_t local[3] = {0, 0, 0}, total[3] = {0, 0, 0};
  if (stats) local[0] = stats->evaluations, local[1] = stats->escaped, local[2] = stats->non_finite;
  MPI_Reduce(local, total, 3, MPI_INT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
  if (rank != 0) return false;
  if (stats) stats->evaluations = total[0], stats->escaped = total[1], stats->non_finite = total[2];
  *mesh = WeldTilePieces(plan, pieces, summary, band);
  const double t_weld = Now();
  if (summary) summary->seconds = t_weld - t0;
  const json timing = {{"ranks", P},
                       {"threads_per_rank", omp_get_max_threads()},
                       {"search_seconds", t_plan - t0},
                       {"mesh_seconds", t_mesh - t_plan},
                       {"weld_seconds", t_weld - t_mesh},
                       {"tiles", plan.tile_ids.size()},
                       {"tiles_by_rank", report.tiles_by_rank},
                       {"bytes_received", report.bytes_received}};
  std::fprintf(stderr, "quijibo-mpi: %s\n", timing.dump().c_str());
  return true;
}

// ---------------------------------------------------------------------------------------------
// sweep

struct Job {
  std::string name;
  std::vector<std::string> args;
  json params = json::object();
};

std::string Sanitize(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '_';
  return o;
}

std::string ValueText(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

std::string Substitute(std::string s, const std::map<std::string, std::string>& vars) {
  for (const auto& [k, v] : vars) {
    const std::string key = "{" + k + "}";
    for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + v.size())) s.replace(at, key.size(), v);
  }
  return s;
}

// SWEEP.json: {"out": folder, "args": [...template...], "grid": {"alpha": [..], ...}, "jobs": [{"name", "args"}]}.
std::vector<Job> ReadSweep(const json& doc, const std::filesystem::path& out) {
  std::vector<Job> jobs;
  auto finish = [&](Job& j, std::vector<std::string> templ) {
    const std::filesystem::path dir = out / j.name;
    std::map<std::string, std::string> vars{{"dir", dir.string()}, {"name", j.name}, {"out", out.string()}};
    for (auto it = j.params.begin(); it != j.params.end(); ++it) vars[it.key()] = ValueText(it.value());
    for (auto& a : templ) a = Substitute(a, vars);
    j.args = std::move(templ);
    jobs.push_back(std::move(j));
  };
  if (doc.contains("grid")) {
    if (!doc.contains("args")) throw Error("sweep: \"grid\" needs an \"args\" template");
    const auto templ = doc.at("args").get<std::vector<std::string>>();
    std::vector<std::string> keys;
    std::vector<std::vector<json>> values;
    for (auto it = doc.at("grid").begin(); it != doc.at("grid").end(); ++it) {
      keys.push_back(it.key());
      values.push_back(it.value().get<std::vector<json>>());
      if (values.back().empty()) throw Error("sweep: grid \"" + it.key() + "\" has no values");
    }
    std::vector<std::size_t> at(keys.size(), 0);
    for (bool more = !keys.empty(); more;) {
      Job j;
      j.name = std::to_string(jobs.size());
      j.name.insert(0, 4 - std::min<std::size_t>(4, j.name.size()), '0');
      for (std::size_t k = 0; k < keys.size(); ++k) {
        j.params[keys[k]] = values[k][at[k]];
        j.name += "_" + Sanitize(keys[k] + "-" + ValueText(values[k][at[k]]));
      }
      finish(j, templ);
      more = false;
      for (std::size_t k = keys.size(); k-- > 0;) {  // the last key fastest
        if (++at[k] < values[k].size()) {
          more = true;
          break;
        }
        at[k] = 0;
      }
    }
  }
  if (doc.contains("jobs"))
    for (const auto& e : doc.at("jobs")) {
      Job j;
      j.name = Sanitize(e.value("name", "job" + std::to_string(jobs.size())));
      if (e.contains("params")) j.params = e.at("params");
      finish(j, e.at("args").get<std::vector<std::string>>());
    }
  if (jobs.empty()) throw Error("sweep: no jobs (give \"grid\" + \"args\", or \"jobs\")");
  for (std::size_t i = 0; i < jobs.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (jobs[i].name == jobs[k].name) throw Error("sweep: two jobs named " + jobs[i].name);
  return jobs;
}

// Starts `quijibo args...` in job's folder, stdout and stderr to files there.
pid_t Spawn(const std::string& exe, const Job& job, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  const std::string out = (dir / "stdout.txt").string(), err = (dir / "stderr.txt").string();
  posix_spawn_file_actions_addopen(&fa, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<std::string> argv_s{exe, "-q"};
  argv_s.insert(argv_s.end(), job.args.begin(), job.args.end());
  std::vector<char*> argv;
  for (auto& s : argv_s) argv.push_back(s.data());
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, exe.c_str(), &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc != 0) return -1;
  return pid;
}

int ExitCode(int status) { return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status); }

json JobResult(const Job& job, const std::filesystem::path& out, int rank, int code, double seconds) {
  return {{"name", job.name}, {"args", job.args}, {"params", job.params}, {"dir", (out / job.name).string()},
          {"rank", rank}, {"exit_code", code}, {"seconds", seconds}};
}

void AddSweep(CLI::App& app) {
  struct Args {
    std::string sweep, out, exe;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand("sweep", "Run a list or grid of `quijibo` commands, one job per rank at a time "
                                            "(dynamic), results in one folder with index.json");
  c->add_option("sweep", a->sweep, "SWEEP.json (docs/mpi.md)")->required();
  c->add_option("-o,--out", a->out, "Results folder (default: the file's \"out\", else sweep-results)");
  c->add_option("--quijibo", a->exe, "The quijibo executable (default: next to quijibo-mpi)");
  c->callback([a] {
    const int P = Size(), rank = Rank();
    std::ifstream in(a->sweep);
    if (!in) throw Error(a->sweep + ": cannot read");
    const json doc = json::parse(in);
    std::filesystem::path out = a->out.empty() ? doc.value("out", std::string("sweep-results")) : a->out;
    out = std::filesystem::absolute(out);
    std::string exe = a->exe;
    if (exe.empty()) exe = (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "quijibo").string();
    if (::access(exe.c_str(), X_OK) != 0) throw Error("sweep: " + exe + " is not executable (see --quijibo)");
    const std::vector<Job> jobs = ReadSweep(doc, out);
    if (rank == 0) std::filesystem::create_directories(out);
    MPI_Barrier(MPI_COMM_WORLD);
    if (rank != 0) {
      // Worker: ask, run, report.
      std::string report = "{}";
      for (;;) {
        SendBytes(std::vector<char>(report.begin(), report.end()), 0, kTagResult);
        std::int64_t index = -1;
        MPI_Recv(&index, 1, MPI_INT64_T, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (index < 0) return;
        const Job& job = jobs[std::size_t(index)];
        const double t = Now();
        const pid_t pid = Spawn(exe, job, out / job.name);
        int status = 0, code = 127;
        if (pid > 0 && ::waitpid(pid, &status, 0) == pid) code = ExitCode(status);
        json r = JobResult(job, out, rank, code, Now() - t);
        r["index"] = index;
        report = r.dump();
      }
    }
    // Rank 0: the queue, and one job of its own at a time.
    std::vector<json> results(jobs.size());
    std::int64_t next = 0, done = 0;
    int stopped = 0;
    pid_t own = -1;
    std::int64_t own_index = -1;
    double own_start = 0;
    const std::int64_t n = std::int64_t(jobs.size());
    Progress progress("sweep", double(n), false);
    auto finished = [&](std::int64_t index, json r) {
      results[std::size_t(index)] = std::move(r);
      ++done;
      progress.update(double(done), std::to_string(done) + " of " + std::to_string(n) + " jobs");
    };
    while (done < n || stopped < P - 1) {
      bool busy = false;
      if (own > 0) {
        int status = 0;
        if (::waitpid(own, &status, WNOHANG) == own) {
          finished(own_index, JobResult(jobs[std::size_t(own_index)], out, 0, ExitCode(status), Now() - own_start));
          own = -1;
          busy = true;
        }
      }
      if (own <= 0 && next < n) {
        own_index = next++;
        own_start = Now();
        own = Spawn(exe, jobs[std::size_t(own_index)], out / jobs[std::size_t(own_index)].name);
        if (own <= 0) {
          finished(own_index, JobResult(jobs[std::size_t(own_index)], out, 0, 127, 0.0));
          own = -1;
        }
        busy = true;
      }
      int flag = 0;
      MPI_Status st;
      MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &flag, &st);
      if (flag) {
        const std::vector<char> bytes = ReceiveBytes(st);
        json r = json::parse(std::string(bytes.begin(), bytes.end()));
        if (r.contains("index")) {
          const auto index = r["index"].get<std::int64_t>();
          r.erase("index");
          finished(index, std::move(r));
        }
        std::int64_t index = next < n ? next++ : -1;
        if (index < 0) ++stopped;
        MPI_Send(&index, 1, MPI_INT64_T, st.MPI_SOURCE, kTagWork, MPI_COMM_WORLD);
        busy = true;
      }
      if (!busy) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    progress.finish();
    int failed = 0;
    for (const auto& r : results) failed += r["exit_code"].get<int>() != 0;
    const json index = {{"sweep", std::filesystem::absolute(a->sweep).string()}, {"quijibo", exe}, {"ranks", P},
                        {"jobs", results}, {"failed", failed}};
    cli::WriteOutput((out / "index.json").string(), index.dump(2) + "\n");
    std::fprintf(stderr, "quijibo-mpi: sweep: %zu jobs on %d ranks, %d failed; %s\n", jobs.size(), P, failed,
                 (out / "index.json").string().c_str());
    if (failed) throw Error("sweep: " + std::to_string(failed) + " job(s) failed (see index.json)");
  });
}

}  // namespace
}  // namespace quijibo::mpi

int main(int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const int rank = quijibo::mpi::Rank(), size = quijibo::mpi::Size();
  int code = 0;
  {
    CLI::App app{"quijibo-mpi: `quijibo mesh` distributed over MPI ranks, and parameter sweeps (docs/mpi.md).\n"
                 "Run it under mpirun/srun; every rank gets the same arguments."};
    app.set_version_flag("--version", "quijibo-mpi 0.1.0");
    app.require_subcommand(1);
    bool quiet = false;
    app.add_flag("-q,--quiet", quiet, "No progress on stderr");
    app.parse_complete_callback([&] { quijibo::Progress::globally_quiet() = quiet || rank != 0; });
    quijibo::cli::AddMeshCommand(app, quijibo::mpi::MpiMesher);
    quijibo::mpi::AddSweep(app);
    try {
      app.parse(argc, argv);
    } catch (const CLI::Success& e) {
      code = rank == 0 ? app.exit(e) : 0;
    } catch (const CLI::ParseError& e) {
      if (rank == 0) code = app.exit(e);
      else code = e.get_exit_code();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "quijibo-mpi: error (rank %d of %d): %s\n", rank, size, e.what());
      code = 1;
      // Other ranks may be waiting on this one.
      if (size > 1) MPI_Abort(MPI_COMM_WORLD, code);
    }
  }
  MPI_Finalize();
  return code;
}
