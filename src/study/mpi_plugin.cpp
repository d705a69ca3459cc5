// The plugin libtrochomill_mpi.so (mpi_plugin.hpp): the sweep's MPI calls.
#include "mpi_plugin.hpp"

#include <mpi.h>

#include "trochomill/error.hpp"

namespace trochomill::study_detail {
namespace {

void init(int* rank, int* size) {
  int provided = 0;
  if (MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
    throw Error("MPI_Init_thread failed");
  }
  if (provided < MPI_THREAD_FUNNELED) {
    MPI_Finalize();
    throw Error("the MPI library gives no thread support (MPI_THREAD_FUNNELED is needed)");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, rank);
  MPI_Comm_size(MPI_COMM_WORLD, size);
}

void finalize() noexcept { MPI_Finalize(); }

void send_bytes(const std::string& data, int dest, int tag) {
  MPI_Send(data.data(), static_cast<int>(data.size()), MPI_CHAR, dest, tag, MPI_COMM_WORLD);
}

void send_int64(const std::int64_t* values, int count, int dest, int tag) {
  MPI_Send(values, count, MPI_INT64_T, dest, tag, MPI_COMM_WORLD);
}

void recv_int64(std::int64_t* values, int count, int source, int tag) {
  MPI_Recv(values, count, MPI_INT64_T, source, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

bool probe_bytes(int tag, int* source, int* count) {
  int flag = 0;
  MPI_Status status;
  MPI_Iprobe(MPI_ANY_SOURCE, tag, MPI_COMM_WORLD, &flag, &status);
  if (!flag) return false;
  *source = status.MPI_SOURCE;
  MPI_Get_count(&status, MPI_CHAR, count);
  return true;
}

void recv_bytes(std::string& into, int count, int source, int tag) {
  into.resize(static_cast<std::size_t>(count));
  MPI_Recv(into.data(), count, MPI_CHAR, source, tag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
}

int bcast_int(int value) {
  MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return value;
}

const MpiTable kTable{&init,       &finalize,    &send_bytes, &send_int64,
                      &recv_int64, &probe_bytes, &recv_bytes, &bcast_int};

}  // namespace
}  // namespace trochomill::study_detail

extern "C" __attribute__((visibility("default"))) const trochomill::study_detail::MpiTable*
trochomill_mpi_table() {
  return &trochomill::study_detail::kTable;
}
