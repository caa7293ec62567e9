// Cells of a study over MPI ranks (VIBRO_MPI) or one process. OpenMPI is reached through the
// plugin libvibro_mpi.so (studies/mpi_api.hpp), loaded only when mpirun started this process.
#include "vibro/distribute.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <stdexcept>
#include <string>

#ifdef VIBRO_MPI
#include "dynamics/plugin_loader.hpp"
#include "studies/mpi_api.hpp"
#endif

namespace vibro {
namespace {

#ifdef VIBRO_MPI
// mpirun (OpenMPI, or a PMI/PMIx launcher) marks the processes it starts.
bool LaunchedByMpirun() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK"})
    if (std::getenv(v)) return true;
  return false;
}

void MpiCheck(int rc, const char* what) {
  if (rc != 0) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}

// RTLD_GLOBAL: OpenMPI's own components, which it dlopens in turn, resolve their symbols against
// libmpi and libopen-pal.
const VibroMpiApi* LoadMpi() {
  const detail::LoadedPlugin plugin =
      detail::LoadPlugin({VIBRO_MPI_PLUGIN, "vibro_mpi_api", true, "MPI: ", "", ", which a run under mpirun needs"});
  return reinterpret_cast<const VibroMpiApi* (*)()>(plugin.entry)();
}
#endif

}  // namespace

bool Distribution::Built() {
#ifdef VIBRO_MPI
  return true;
#else
  return false;
#endif
}

Distribution::Distribution() {
#ifdef VIBRO_MPI
  if (!LaunchedByMpirun()) return;
  mpi_ = LoadMpi();
  int joined = 0;
  MpiCheck(mpi_->join(&joined, &rank_, &size_), "MPI_Init_thread");
  joined_ = joined != 0;
#endif
}

Distribution::~Distribution() {
#ifdef VIBRO_MPI
  if (joined_) mpi_->finalize();
#endif
}

bool Distribution::Any(bool flag) const {
#ifdef VIBRO_MPI
  if (size_ > 1) {
    int out = 0;
    MpiCheck(mpi_->any(flag ? 1 : 0, &out), "MPI_Allreduce");
    return out != 0;
  }
#endif
  return flag;
}

long long Distribution::Broadcast(long long value) const {
#ifdef VIBRO_MPI
  if (size_ > 1) MpiCheck(mpi_->broadcast(&value, 1), "MPI_Bcast");
#endif
  return value;
}

void Distribution::Broadcast(std::vector<std::size_t>& values) const {
#ifdef VIBRO_MPI
  if (size_ <= 1) return;
  std::vector<unsigned long long> v(values.begin(), values.end());
  auto n = static_cast<long long>(v.size());
  n = Broadcast(n);
  v.resize(static_cast<std::size_t>(n));
  MpiCheck(mpi_->broadcast_unsigned(v.data(), static_cast<int>(n)), "MPI_Bcast");
  values.assign(v.begin(), v.end());
#else
  (void)values;
#endif
}

void Distribution::GatherCells(const std::vector<std::size_t>& batch,
                               std::vector<CellResult>& cells) const {
#ifdef VIBRO_MPI
  if (size_ <= 1) return;
  std::vector<double> mine;
  for (std::size_t i = static_cast<std::size_t>(rank_); i < batch.size(); i += static_cast<std::size_t>(size_))
    PackCell(cells[batch[i]], mine);
  int count = static_cast<int>(mine.size());
  std::vector<int> counts(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
  MpiCheck(mpi_->gather_count(count, counts.data()), "MPI_Gather");
  std::vector<double> all;
  if (root()) {
    int total = 0;
    for (int r = 0; r < size_; ++r) {
      offsets[static_cast<std::size_t>(r)] = total;
      total += counts[static_cast<std::size_t>(r)];
    }
    all.resize(static_cast<std::size_t>(total));
  }
  MpiCheck(mpi_->gather_doubles(mine.data(), count, all.data(), counts.data(), offsets.data()),
           "MPI_Gatherv");
  if (!root()) return;
  for (int r = 1; r < size_; ++r) {
    const double* p = all.data() + offsets[static_cast<std::size_t>(r)];
    for (std::size_t i = static_cast<std::size_t>(r); i < batch.size(); i += static_cast<std::size_t>(size_))
      cells[batch[i]] = UnpackCell(p);
  }
#else
  (void)batch;
  (void)cells;
#endif
}

void RunPendingCells(const System& sys, const Scene& scene, const Coordinate& a, const Coordinate& b,
                     const std::vector<std::pair<double, double>>& points,
                     std::vector<CellResult>& cells, const StudyOptions& options,
                     const Distribution& dist,
                     const std::function<void(const std::vector<std::size_t>&)>& on_batch) {
  std::vector<std::size_t> pending;
  if (dist.root())
    for (std::size_t i = 0; i < cells.size(); ++i)
      if (cells[i].state == CellResult::State::kPending) pending.push_back(i);
  dist.Broadcast(pending);
  const auto total = static_cast<long long>(pending.size());
  long long batch_size = 256, done = 0;
  StudyOptions opt = options;
  for (std::size_t first = 0; first < pending.size();) {
    const std::size_t last = std::min(pending.size(), first + static_cast<std::size_t>(batch_size));
    const std::vector<std::size_t> batch(pending.begin() + static_cast<std::ptrdiff_t>(first),
                                         pending.begin() + static_cast<std::ptrdiff_t>(last));
    std::vector<std::size_t> mine;
    for (std::size_t i = static_cast<std::size_t>(dist.rank()); i < batch.size(); i += static_cast<std::size_t>(dist.size()))
      mine.push_back(batch[i]);
    if (options.progress)
      opt.progress = [&](long long d, long long) { options.progress(done + d * dist.size(), total); };
    const auto t0 = std::chrono::steady_clock::now();
    RunCells(sys, scene, a, b, points, mine, cells, opt);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    dist.GatherCells(batch, cells);
    if (dist.root()) on_batch(batch);
    done += static_cast<long long>(batch.size());
    first = last;
    if (dist.Any(options.stop_requested && options.stop_requested->load())) break;
    // About a second of work per batch (the root's measure decides for every rank).
    const double grow = seconds > 0 ? 1.0 / seconds : 4.0;
    batch_size = dist.Broadcast(std::clamp<long long>(
        static_cast<long long>(static_cast<double>(batch_size) * std::clamp(grow, 0.25, 4.0)), 64,
        1 << 16));
  }
}

}  // namespace vibro
