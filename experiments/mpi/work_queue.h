// The work queue of quijibo-mpi (docs/mpi.md), shared by meshing (tiles) and sweeps (jobs): rank 0
// hands out batches of item indices on request and does work of its own between requests; each
// worker asks with the results of its last batch, and an empty batch tells it to stop.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <vector>

#include "util/error.h"

namespace quijibo::mpi {

int Rank();
int Size();

// Byte buffers for messages.
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

// Rank 0's side.
struct Coordinator {
  // The next batch for a rank with `threads` threads; empty when no item is left.
  std::function<std::vector<std::int64_t>(int threads)> take;
  // A worker's results (the bytes its `run` returned; not called for the first request).
  std::function<void(int rank, const std::vector<char>& results)> receive;
  // Rank 0's own work: collects a finished batch of its own, starts the next (with `take`);
  // true when it did anything.
  std::function<bool()> own;
  // Every item done and collected.
  std::function<bool()> finished;
};
// Serves the workers until every item is done and every worker has been told to stop. Sleeps
// briefly when idle (not a busy wait).
void Coordinate(const Coordinator& c);

// A worker's side: asks for batches until told to stop; `run` does a batch and returns its
// results. `threads` tells rank 0 how large a batch this rank takes.
void Work(int threads, const std::function<std::vector<char>(const std::vector<std::int64_t>& batch)>& run);

}  // namespace quijibo::mpi
