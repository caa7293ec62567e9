// libvibro_mpi.so: the MPI entry points of src/studies/mpi_api.hpp over OpenMPI's C API. The only
// file of vibro that includes mpi.h; libvibro loads it (dlopen) only when mpirun started the process.
#include <mpi.h>

#include "studies/mpi_api.hpp"

namespace {

int Join(int* joined, int* rank, int* size) {
  int initialized = 0, rc = MPI_Initialized(&initialized);
  *joined = 0;
  if (rc == MPI_SUCCESS && !initialized) {
    int provided = 0;
    // Only the main thread talks to MPI; oneTBB workers compute cells.
    rc = MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    if (rc == MPI_SUCCESS) *joined = 1;
  }
  if (rc == MPI_SUCCESS) rc = MPI_Comm_rank(MPI_COMM_WORLD, rank);
  if (rc == MPI_SUCCESS) rc = MPI_Comm_size(MPI_COMM_WORLD, size);
  return rc;
}

int Finalize() { return MPI_Finalize(); }

int Any(int flag, int* out) { return MPI_Allreduce(&flag, out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD); }

int Broadcast(long long* values, int count) {
  return MPI_Bcast(values, count, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
}

int BroadcastUnsigned(unsigned long long* values, int count) {
  return MPI_Bcast(values, count, MPI_UNSIGNED_LONG_LONG, 0, MPI_COMM_WORLD);
}

int GatherCount(int count, int* counts) {
  return MPI_Gather(&count, 1, MPI_INT, counts, 1, MPI_INT, 0, MPI_COMM_WORLD);
}

int GatherDoubles(const double* mine, int count, double* all, const int* counts, const int* offsets) {
  return MPI_Gatherv(mine, count, MPI_DOUBLE, all, counts, offsets, MPI_DOUBLE, 0, MPI_COMM_WORLD);
}

constexpr VibroMpiApi kApi{Join, Finalize, Any, Broadcast, BroadcastUnsigned, GatherCount, GatherDoubles};

}  // namespace

extern "C" __attribute__((visibility("default"))) const VibroMpiApi* vibro_mpi_api() { return &kApi; }
