// Open MPI for the sweep's ranks, behind the plugin libtrochomill_mpi.so (mpi_plugin.cpp):
// linked into the program, Open MPI costs every start about 6 ms, and only a run that mpirun
// started uses it. The protocol (distributed.cpp) stays here; the plugin makes the calls.
#pragma once

#include <cstdint>
#include <string>

namespace trochomill::study_detail {

/// The plugin's functions (trochomill_mpi_table()), on MPI_COMM_WORLD.
struct MpiTable {
  /// MPI_Init_thread with MPI_THREAD_FUNNELED, then this process's rank and the world's size.
  /// Throws Error when MPI fails or gives no such thread support (MPI finalised then).
  void (*init)(int* rank, int* size);
  void (*finalize)() noexcept;
  /// Blocking sends and receives of bytes (MPI_CHAR) and 64-bit integers.
  void (*send_bytes)(const std::string& data, int dest, int tag);
  void (*send_int64)(const std::int64_t* values, int count, int dest, int tag);
  void (*recv_int64)(std::int64_t* values, int count, int source, int tag);
  /// Whether a message with `tag` from any rank waits (MPI_Iprobe): its source and size.
  bool (*probe_bytes)(int tag, int* source, int* count);
  void (*recv_bytes)(std::string& into, int count, int source, int tag);
  /// Rank 0's value, on every rank (MPI_Bcast).
  int (*bcast_int)(int value);
};
inline constexpr const char* kMpiSymbol = "trochomill_mpi_table";

}  // namespace trochomill::study_detail
