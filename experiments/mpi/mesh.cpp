// quijibo-mpi mesh: every rank builds the field; the sparse search's lattice is split evenly over the
// ranks (Allgatherv, so every rank holds the same tile plan); then rank 0 hands out batches of tiles
// on demand over the work queue (tiles differ wildly in surface), meshes batches itself on a second
// thread, receives the pieces (vertices keyed by global edge id) as they finish, welds them in tile
// order and writes (or, with --stream, streams them to the PLY as they arrive: MeshStreamWriter).
// The result does not depend on which rank meshed which tile: it is the
// single-process mesh, bit for bit.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cstdio>
#include <functional>
#include <future>
#include <memory>
#include <nlohmann/json.hpp>

#include "experiments/mpi/mpi.h"
#include "experiments/mpi/work_queue.h"
#include "util/progress.h"

namespace quijibo::mpi {

using nlohmann::json;

namespace {

double Now() { return MPI_Wtime(); }

void PackPiece(Writer& w, std::int64_t index, const mesh::TilePiece& p) {
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

std::int64_t UnpackPiece(Reader& r, mesh::TilePiece& p) {
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

// The sparse search's lattice split evenly over the ranks (contiguous slices), gathered everywhere.
mesh::PointsEvaluator SpreadSearch(const mesh::BatchField& field) {
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
  const std::int64_t want =
      std::max<std::int64_t>(threads, std::min<std::int64_t>(4 * threads, remaining / (4 * ranks)));
  return std::min(remaining, want);
}

std::vector<std::pair<std::int64_t, mesh::TilePiece>> MeshBatch(const mesh::BatchField& field,
                                                                const mesh::TilePlan& plan,
                                                                const std::vector<std::int64_t>& batch,
                                                                bool want_band) {
  std::vector<std::pair<std::int64_t, mesh::TilePiece>> out(batch.size());
#pragma omp parallel for schedule(dynamic)
  for (std::int64_t i = 0; i < std::int64_t(batch.size()); ++i) {
    out[std::size_t(i)].first = batch[std::size_t(i)];
    out[std::size_t(i)].second = mesh::MeshTilePiece(field, plan, std::size_t(batch[std::size_t(i)]), want_band);
  }
  return out;
}

struct CoordinatorReport {
  std::vector<std::int64_t> tiles_by_rank;
  std::int64_t bytes_received = 0;
};

// Rank 0: the tiles through the work queue; its own batches run on a second thread (MPI stays on
// this one). Every piece goes to `consume` (on this thread) as it arrives.
using Consumer = std::function<void(std::int64_t index, mesh::TilePiece&& piece)>;
void MeshTiles(const mesh::BatchField& field, const mesh::TilePlan& plan, bool want_band, bool progress_on,
               CoordinatorReport& report, const Consumer& consume) {
  const int P = Size();
  const std::int64_t n = std::int64_t(plan.tile_ids.size());
  report.tiles_by_rank.assign(std::size_t(P), 0);
  std::int64_t next = 0, received = 0;
  const int own_threads = omp_get_max_threads();
  std::future<std::vector<std::pair<std::int64_t, mesh::TilePiece>>> own;
  Progress progress("mesh: tiles", double(n), !progress_on);
  auto store = [&](std::int64_t index, mesh::TilePiece&& piece, int rank) {
    if (index < 0 || index >= n) throw Error("quijibo-mpi: a worker sent an unknown tile");
    consume(index, std::move(piece));
    ++received;
    ++report.tiles_by_rank[std::size_t(rank)];
    progress.update(double(received),
                    std::to_string(received) + " of " + std::to_string(n) + " tiles, " + std::to_string(P) + " ranks");
  };
  Coordinator c;
  c.take = [&](int threads) {
    const std::int64_t m = BatchSize(n - next, threads, P);
    std::vector<std::int64_t> batch(static_cast<std::size_t>(m));
    for (std::int64_t i = 0; i < m; ++i) batch[std::size_t(i)] = next++;
    return batch;
  };
  c.receive = [&](int rank, const std::vector<char>& bytes) {
    report.bytes_received += std::int64_t(bytes.size());
    Reader r{bytes};
    const auto count = r.pod<std::int64_t>();
    for (std::int64_t i = 0; i < count; ++i) {
      mesh::TilePiece piece;
      const std::int64_t index = UnpackPiece(r, piece);
      store(index, std::move(piece), rank);
    }
  };
  c.own = [&] {
    bool busy = false;
    if (own.valid() && own.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      for (auto& [index, piece] : own.get()) store(index, std::move(piece), 0);
      busy = true;
    }
    if (!own.valid() && next < n) {
      own = std::async(std::launch::async, [&field, &plan, want_band, batch = c.take(own_threads)] {
        return MeshBatch(field, plan, batch, want_band);
      });
      busy = true;
    }
    return busy;
  };
  c.finished = [&] { return received == n && !own.valid(); };
  Coordinate(c);
  progress.finish();
}

// The workers' side: batches of tiles meshed and sent back to rank 0.
void WorkTiles(const mesh::BatchField& field, const mesh::TilePlan& plan, bool want_band) {
  Work(omp_get_max_threads(), [&](const std::vector<std::int64_t>& batch) {
    Writer w;
    const auto done = MeshBatch(field, plan, batch, want_band);
    w.pod(std::int64_t(done.size()));
    for (const auto& [index, piece] : done) PackPiece(w, index, piece);
    return w.bytes;
  });
}

// The field's counters, summed on rank 0.
void ReduceStats(mesh::JuliaFieldStats* stats) {
  std::int64_t local[4] = {0, 0, 0, 0}, total[4] = {0, 0, 0, 0};
  if (stats)
    local[0] = stats->evaluations, local[1] = stats->escaped, local[2] = stats->non_finite,
    local[3] = stats->applications;
  MPI_Reduce(local, total, 4, MPI_INT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
  if (stats && Rank() == 0)
    stats->evaluations = total[0], stats->escaped = total[1], stats->non_finite = total[2],
    stats->applications = total[3];
}

void PrintTiming(double t0, double t_plan, double t_mesh, double t_weld, const mesh::TilePlan& plan,
                 const CoordinatorReport& report, bool streamed) {
  const json timing = {{"ranks", Size()},
                       {"threads_per_rank", omp_get_max_threads()},
                       {"search_seconds", t_plan - t0},
                       {"mesh_seconds", t_mesh - t_plan},
                       {streamed ? "finish_seconds" : "weld_seconds", t_weld - t_mesh},
                       {"streamed", streamed},
                       {"tiles", plan.tile_ids.size()},
                       {"tiles_by_rank", report.tiles_by_rank},
                       {"bytes_received", report.bytes_received}};
  std::fprintf(stderr, "quijibo-mpi: %s\n", timing.dump().c_str());
}

}  // namespace

bool MpiMesher(const mesh::BatchField& field, const mesh::MeshingOptions& options, mesh::MeshingSummary* summary,
               mesh::FieldBand* band, mesh::TriangleMesh* mesh, mesh::JuliaFieldStats* stats) {
  const int P = Size(), rank = Rank();
  const double t0 = Now();
  const mesh::TilePlan plan = mesh::PlanTiles(field, options, P > 1 ? SpreadSearch(field) : mesh::PointsEvaluator{});
  const double t_plan = Now();
  const bool want_band = band != nullptr;
  std::vector<mesh::TilePiece> pieces;
  CoordinatorReport report;
  if (rank == 0) {
    pieces.resize(plan.tile_ids.size());
    MeshTiles(field, plan, want_band, options.show_progress, report,
              [&](std::int64_t index, mesh::TilePiece&& piece) { pieces[std::size_t(index)] = std::move(piece); });
  } else {
    WorkTiles(field, plan, want_band);
  }
  const double t_mesh = Now();
  ReduceStats(stats);
  if (rank != 0) return false;
  *mesh = mesh::WeldTilePieces(plan, pieces, summary, band);
  const double t_weld = Now();
  if (summary) summary->seconds = t_weld - t0;
  PrintTiming(t0, t_plan, t_mesh, t_weld, plan, report, false);
  return true;
}

std::optional<mesh::MeshStreamReport> MpiStreamMesher(const mesh::BatchField& field,
                                                      const mesh::MeshingOptions& options,
                                                      const mesh::MeshStreamOptions& stream,
                                                      mesh::MeshingSummary* summary, mesh::JuliaFieldStats* stats) {
  const int P = Size(), rank = Rank();
  const double t0 = Now();
  const mesh::TilePlan plan = mesh::PlanTiles(field, options, P > 1 ? SpreadSearch(field) : mesh::PointsEvaluator{});
  const double t_plan = Now();
  const bool want_band = stream.band != nullptr;
  CoordinatorReport report;
  std::unique_ptr<mesh::MeshStreamWriter> writer;
  if (rank == 0) {
    writer = std::make_unique<mesh::MeshStreamWriter>(plan, stream);
    MeshTiles(field, plan, want_band, options.show_progress, report,
              [&](std::int64_t index, mesh::TilePiece&& piece) { writer->Add(std::size_t(index), std::move(piece)); });
  } else {
    WorkTiles(field, plan, want_band);
  }
  const double t_mesh = Now();
  ReduceStats(stats);
  if (rank != 0) return std::nullopt;
  const mesh::MeshStreamReport r = writer->Finish(summary);
  const double t_done = Now();
  if (summary) summary->seconds = t_done - t0;
  PrintTiming(t0, t_plan, t_mesh, t_done, plan, report, true);
  return r;
}

}  // namespace quijibo::mpi
