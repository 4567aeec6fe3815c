#include "experiments/mpi/work_queue.h"

#include <chrono>
#include <climits>
#include <thread>

namespace quijibo::mpi {

namespace {

constexpr int kTagWork = 11, kTagResult = 12;

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

}  // namespace

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

void Coordinate(const Coordinator& c) {
  const int P = Size();
  int stopped = 0;
  while (!c.finished() || stopped < P - 1) {
    bool busy = c.own();
    int flag = 0;
    MPI_Status st;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &flag, &st);
    if (flag) {
      const std::vector<char> bytes = ReceiveBytes(st);
      Reader r{bytes};
      const int threads = std::max(1, int(r.pod<std::int32_t>()));
      const std::vector<char> results(bytes.begin() + std::ptrdiff_t(r.at), bytes.end());
      if (!results.empty()) c.receive(st.MPI_SOURCE, results);
      const std::vector<std::int64_t> batch = c.take(threads);
      if (batch.empty()) ++stopped;
      MPI_Send(batch.data(), int(batch.size()), MPI_INT64_T, st.MPI_SOURCE, kTagWork, MPI_COMM_WORLD);
      busy = true;
    }
    if (!busy) std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

void Work(int threads, const std::function<std::vector<char>(const std::vector<std::int64_t>&)>& run) {
  Writer w;
  w.pod(std::int32_t(threads));
  for (;;) {
    SendBytes(w.bytes, 0, kTagResult);
    MPI_Status st;
    MPI_Probe(0, kTagWork, MPI_COMM_WORLD, &st);
    int count = 0;
    MPI_Get_count(&st, MPI_INT64_T, &count);
    std::vector<std::int64_t> batch(std::size_t(std::max(count, 0)));
    MPI_Recv(batch.data(), count, MPI_INT64_T, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (batch.empty()) return;
    const std::vector<char> results = run(batch);
    w.bytes.clear();
    w.pod(std::int32_t(threads));
    w.bytes.insert(w.bytes.end(), results.begin(), results.end());
  }
}

}  // namespace quijibo::mpi
