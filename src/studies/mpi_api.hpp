// The MPI calls a distributed study makes, as a table of C entry points. The table is exported by
// the plugin libvibro_mpi.so (src/studies/mpi_plugin.cpp, the only file that includes the MPI header) and
// loaded by src/studies/distribute.cpp only in a process started by mpirun: every other vibro
// process (`vibro --version`, `vibro simulate`, a basin on threads) never maps OpenMPI
// (docs/performance.md, "Start-up").
//
// Every entry returns MPI's error code (0 = MPI_SUCCESS). Collectives are over MPI_COMM_WORLD,
// rooted at rank 0.
#pragma once

extern "C" {

struct VibroMpiApi {
  // MPI_Init_thread(MPI_THREAD_FUNNELED) unless MPI is initialized already (then *joined = 0);
  // the rank and the size of the world.
  int (*join)(int* joined, int* rank, int* size);
  int (*finalize)();
  int (*any)(int flag, int* out);                                  // MPI_Allreduce, MPI_LOR
  int (*broadcast)(long long* values, int count);                  // MPI_Bcast, MPI_LONG_LONG
  int (*broadcast_unsigned)(unsigned long long* values, int count);  // MPI_UNSIGNED_LONG_LONG
  int (*gather_count)(int count, int* counts);                     // MPI_Gather of one int
  int (*gather_doubles)(const double* mine, int count, double* all, const int* counts,
                        const int* offsets);                       // MPI_Gatherv
};

// The plugin's one exported symbol.
const VibroMpiApi* vibro_mpi_api();
}

// The plugin's file name; distribute.cpp looks for it beside the object libvibro is in.
#define VIBRO_MPI_PLUGIN "libvibro_mpi.so"
