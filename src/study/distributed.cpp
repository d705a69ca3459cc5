// MPI for the sweep: the world of a run started by mpirun, and the points handed out by rank 0
// to whichever rank asks. The MPI calls are the plugin's (mpi_plugin.hpp), loaded only in a
// run that mpirun started. Without MPI in the build, one rank and no MPI call.
#include "distributed.hpp"

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>

#include "mpi_plugin.hpp"
#include "trochomill/common/plugin.hpp"
#include "trochomill/error.hpp"

namespace trochomill {
namespace {

// Looked up once (every message goes through it); a failed load is tried again next call.
const study_detail::MpiTable& mpi() {
  static const study_detail::MpiTable& table = plugin_table<study_detail::MpiTable>(
      "mpi", study_detail::kMpiSymbol, "a sweep under mpirun (Open MPI)");
  return table;
}

}  // namespace

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
  mpi().init(&rank_, &size_);
  initialised_ = true;
#endif
}

Distributed::~Distributed() {
  if (initialised_) mpi().finalize();
}

namespace detail {
namespace {

constexpr int kTagResult = 1;  // worker -> 0: position (int64, -1: none yet) then the row
constexpr int kTagWork = 2;    // 0 -> worker: position and point (int64 x 2; position -1: stop)

void send_result(std::int64_t position, const std::string& line) {
  std::string msg(sizeof position, '\0');
  std::memcpy(msg.data(), &position, sizeof position);
  msg += line;
  mpi().send_bytes(msg, 0, kTagResult);
}

}  // namespace

void distribute_points(const Distributed& world, const std::vector<std::size_t>& todo,
                       const std::function<std::string(std::size_t)>& row_of,
                       const std::function<void(std::size_t, std::string)>& row_done,
                       const RunHooks& hooks) {
  if (!Distributed::built_with_mpi()) throw Error("this build has no MPI");
  const study_detail::MpiTable& m = mpi();
  if (world.rank() != 0) {
    send_result(-1, {});
    for (;;) {
      std::int64_t work[2] = {0, 0};
      m.recv_int64(work, 2, 0, kTagWork);
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
    int source = 0, count = 0;
    if (!m.probe_bytes(kTagResult, &source, &count)) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      continue;
    }
    m.recv_bytes(buffer, count, source, kTagResult);
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
    m.send_int64(work, 2, source, kTagWork);
    if (work[0] < 0) --active;
  }
  local.join();
  if (local_error) std::rethrow_exception(local_error);
}

bool agree_to_start(const Distributed& world, bool go) {
  if (Distributed::built_with_mpi() && world.size() > 1) return mpi().bcast_int(go ? 1 : 0) != 0;
  return go;
}

}  // namespace detail
}  // namespace trochomill
