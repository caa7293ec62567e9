// Distribution of a study's cells over processes: MPI when vibro is built with the CMake option
// VIBRO_MPI and started by mpirun, one process otherwise (the same calls, without messages).
// OpenMPI is loaded (dlopen of the plugin libvibro_mpi.so, whose src/studies/mpi_plugin.cpp is the
// only file that includes the MPI header) by the first Distribution of a process started by mpirun, and by
// no other process.
//
// Cells are independent, so they are split deterministically (cell batch[i] goes to rank
// i mod size) and their results gathered on rank 0, which alone labels them and writes the
// output: the answer is bitwise the same for any number of processes and threads.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <utility>
#include <vector>

#include "vibro/scene.hpp"
#include "vibro/studies.hpp"
#include "vibro/system.hpp"

struct VibroMpiApi;  // src/studies/mpi_api.hpp

namespace vibro {

class Distribution {
 public:
  // Joins the MPI job when this process was started by mpirun (and vibro was built with MPI);
  // otherwise a single process. Ends the job (MPI_Finalize) when destroyed.
  Distribution();
  ~Distribution();
  Distribution(const Distribution&) = delete;
  Distribution& operator=(const Distribution&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool root() const { return rank_ == 0; }
  static bool Built();  // whether vibro was built with MPI

  // Collective operations (every rank calls them in the same order).
  bool Any(bool flag) const;                                // logical or over the ranks
  void Broadcast(std::vector<std::size_t>& values) const;   // root's values to every rank
  long long Broadcast(long long value) const;               // root's value
  // Rank r computed cells[batch[i]] for i ≡ r (mod size); afterwards the root holds them all.
  void GatherCells(const std::vector<std::size_t>& batch, std::vector<CellResult>& cells) const;

 private:
  int rank_ = 0, size_ = 1;
  bool joined_ = false;
  const VibroMpiApi* mpi_ = nullptr;  // the plugin's entry points, under mpirun only
};

// Computes the root's pending cells (state kPending) in batches of about a second of work, split
// over the ranks, and calls `on_batch` on the root after each batch with its cell indices (in
// increasing order) once the root holds their results. Stops after the batch during which a
// stop was requested on any rank (cells not finished stay pending).
void RunPendingCells(const System& system, const Scene& scene, const Coordinate& a,
                     const Coordinate& b, const std::vector<std::pair<double, double>>& points,
                     std::vector<CellResult>& cells, const StudyOptions& options,
                     const Distribution& distribution,
                     const std::function<void(const std::vector<std::size_t>&)>& on_batch);

}  // namespace vibro
