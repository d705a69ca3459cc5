// MPI for the sweep: the world of a run started by mpirun, and the points handed out by rank 0
// to whichever rank asks. Without MPI in the build, one rank and no MPI call.
#include "distributed.hpp"

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>

#include "trochomill/error.hpp"

#ifdef TROCHOMILL_HAVE_MPI
#include <mpi.h>
#endif

namespace trochomill {

bool Distributed::built_with_mpi() noexcept {
#ifdef TROCHOMILL_HAVE_MPI
  return true;
#else
  return false;
#endif
}

Distributed::Distributed() {
#ifdef TROCHOMILL_HAVE_MPI
  // Only a process mpirun started joins a world: a plain run stays one rank without MPI.
  if (std::getenv("OMPI_COMM_WORLD_SIZE") == nullptr && std::getenv("PMI_SIZE") == nullptr) {
    return;
  }
  int provided = 0;
  if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
    throw Error("MPI_Init_thread failed");
  }
  initialised_ = true;
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw Error("the MPI library gives no thread support (MPI_THREAD_FUNNELED is needed)");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#endif
}

Distributed::~Distributed() {
#ifdef TROCHOMILL_HAVE_MPI
  if (initialised_) MPI_Finalize();
#endif
}

namespace detail {

#ifdef TROCHOMILL_HAVE_MPI
namespace {

constexpr int kTagResult = 1;  // worker -> 0: position (int64, -1: none yet) then the row
constexpr int kTagWork = 2;    // 0 -> worker: position and point (int64 x 2; position -1: stop)

void send_result(std::int64_t position, const std::string& line) {
  std::string msg(sizeof position, '\0');
  std::memcpy(msg.data(), &position, sizeof position);
  msg += line;
  MPI_Send(msg.data(), static_cast<int>(msg.size()), MPI_CHAR, 0, kTagResult, MPI_COMM_WORLD);
}

}  // namespace
#endif

void distribute_points(const Distributed& world, const std::vector<std::size_t>& todo,
                       const std::function<std::string(std::size_t)>& row_of,
                       const std::function<void(std::size_t, std::string)>& row_done,
                       const RunHooks& hooks) {
#ifdef TROCHOMILL_HAVE_MPI
  if (world.rank() != 0) {
    send_result(-1, {});
    for (;;) {
      std::int64_t work[2] = {0, 0};
      MPI_Recv(work, 2, MPI_INT64_T, 0, kTagWork, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      if (work[0] < 0) return;
      send_result(work[0], row_of(static_cast<std::size_t>(work[1])));
    }
  }
  std::atomic<std::size_t> next{0};
  std::mutex mu;
  const auto done = [&](std::size_t position, std::string line) {
    const std::lock_guard<std::mutex> lock(mu);
    row_done(position, std::move(line));
  };
  // Rank 0's own share, on a thread that makes no MPI call (funneled).
  std::exception_ptr local_error;
  std::thread local([&] {
    try {
      for (;;) {
        if (hooks.cancelled()) return;
        const std::size_t p = next.fetch_add(1);
        if (p >= todo.size()) return;
        done(p, row_of(todo[p]));
      }
    } catch (...) {
      local_error = std::current_exception();
    }
  });
  // The others: each message is a result (or a first request); the answer is the next point
  // or the stop. Polled with a short sleep: a blocking receive would spin a core.
  int active = world.size() - 1;
  std::string buffer;
  while (active > 0) {
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kTagResult, MPI_COMM_WORLD, &flag, &status);
    if (!flag) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    int count = 0;
    MPI_Get_count(&status, MPI_CHAR, &count);
    buffer.resize(static_cast<std::size_t>(count));
    MPI_Recv(buffer.data(), count, MPI_CHAR, status.MPI_SOURCE, kTagResult, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    std::int64_t position = -1;
    std::memcpy(&position, buffer.data(), sizeof position);
    if (position >= 0) done(static_cast<std::size_t>(position), buffer.substr(sizeof position));
    std::int64_t work[2] = {-1, -1};
    if (!hooks.cancelled()) {
      const std::size_t p = next.fetch_add(1);
      if (p < todo.size()) {
        work[0] = static_cast<std::int64_t>(p);
        work[1] = static_cast<std::int64_t>(todo[p]);
      }
    }
    MPI_Send(work, 2, MPI_INT64_T, status.MPI_SOURCE, kTagWork, MPI_COMM_WORLD);
    if (work[0] < 0) --active;
  }
  local.join();
  if (local_error) std::rethrow_exception(local_error);
#else
  (void)world, (void)todo, (void)row_of, (void)row_done, (void)hooks;
  throw Error("this build has no MPI");
#endif
}

bool agree_to_start(const Distributed& world, bool go) {
#ifdef TROCHOMILL_HAVE_MPI
  if (world.size() > 1) {
    int flag = go ? 1 : 0;
    MPI_Bcast(&flag, 1, MPI_INT, 0, MPI_COMM_WORLD);
    return flag != 0;
  }
#else
  (void)world;
#endif
  return go;
}

}  // namespace detail
}  // namespace trochomill
