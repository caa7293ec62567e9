// Basin and attractor studies in the store (docs/output.md, /basin and /attractors): the cell
// table written as batches finish, its resume, the label map and the attractor table.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {

namespace store {

void CellTable::Create(h5::Id g, h5::Size zcols) {
  index = h5::Column(g, "index", h5::Type::I64(), 0);
  state = h5::Column(g, "state", h5::Type::I8(), 0);
  kind = h5::Column(g, "kind", h5::Type::I8(), 0);
  period = h5::Column(g, "period", h5::Type::I32(), 0);
  impacts = h5::Column(g, "impacts_per_period", h5::Type::I64(), 0);
  sticking_fraction = h5::Column(g, "sticking_fraction", h5::Type::F64(), 0);
  periods = h5::Column(g, "periods", h5::Type::I64(), 0);
  stop = h5::Column(g, "stop", h5::Type::I8(), 0);
  stick_count = h5::Column(g, "stick_phase_count", h5::Type::I32(), 0);
  impact_count = h5::Column(g, "impact_count", h5::Type::I32(), 0);
  z = h5::Column(g, "z", h5::Type::F64(), zcols);
  phases = h5::Column(g, "phases", h5::Type::F64(), 0);
}

void CellTable::Open(h5::Id g, h5::Size zcols) {
  index = h5::Column::Open(g, "index", h5::Type::I64());
  state = h5::Column::Open(g, "state", h5::Type::I8());
  kind = h5::Column::Open(g, "kind", h5::Type::I8());
  period = h5::Column::Open(g, "period", h5::Type::I32());
  impacts = h5::Column::Open(g, "impacts_per_period", h5::Type::I64());
  sticking_fraction = h5::Column::Open(g, "sticking_fraction", h5::Type::F64());
  periods = h5::Column::Open(g, "periods", h5::Type::I64());
  stop = h5::Column::Open(g, "stop", h5::Type::I8());
  stick_count = h5::Column::Open(g, "stick_phase_count", h5::Type::I32());
  impact_count = h5::Column::Open(g, "impact_count", h5::Type::I32());
  z = h5::Column::Open(g, "z", h5::Type::F64(), zcols);
  phases = h5::Column::Open(g, "phases", h5::Type::F64());
}

void CellTable::Push(size_t i, const CellResult& c, h5::Size zcols) {
  const Attractor& a = c.attractor;
  index.Push(static_cast<std::int64_t>(i));
  state.Push(static_cast<std::int8_t>(c.state));
  kind.Push(static_cast<std::int8_t>(KindCode(a.kind)));
  period.Push(static_cast<std::int32_t>(a.period.value_or(0)));
  impacts.Push(static_cast<std::int64_t>(a.impacts_per_period.value_or(-1)));
  sticking_fraction.Push(a.sticking_fraction.value_or(std::numeric_limits<double>::quiet_NaN()));
  periods.Push(static_cast<std::int64_t>(c.periods));
  stop.Push(c.stop);
  stick_count.Push(static_cast<std::int32_t>(a.stick_phases.size()));
  impact_count.Push(static_cast<std::int32_t>(a.impact_phases.size()));
  Eigen::VectorXd zz = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(zcols));
  if (c.z.size() == zz.size()) zz = c.z;
  z.PushRow(zz);
  for (const auto& [b, e] : a.stick_phases) {
    phases.Push(b);
    phases.Push(e);
  }
  for (double v : a.impact_phases) phases.Push(v);
  for (double v : a.impact_velocities) phases.Push(v);
}

}  // namespace store

namespace {

// The attractors of a study as a table: one dataset per column, row k ↔ label k. Integer
// columns are integers (−1 for a null period or impact count, stable −1 when the orbit was not
// solved), null floats NaN, strings variable-length UTF-8; the multipliers of row k are the
// rows multiplier_offset[k] … + multiplier_count[k] − 1 of floquet_multipliers (M, 2) [re, im].
void WriteAttractorTable(h5::Id f, const StudyResult& st) {
  const h5::Handle table = h5::CreateGroup(f, "/attractors");
  const h5::Id g = table.get();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::int32_t> period, merged, count, offset;
  std::vector<std::int64_t> impacts;
  std::vector<std::int8_t> stable;
  std::vector<double> sp, frac, err, residual, mu, lead, lyap, lyap_lo, lyap_hi;
  std::vector<std::int8_t> chaotic;
  std::vector<std::string> kinds, status;
  for (const auto& a : st.attractors) {
    const store::LyapunovColumns c = store::LyapunovRow(a.lyapunov);
    lyap.push_back(c.largest);
    lyap_lo.push_back(c.low);
    lyap_hi.push_back(c.high);
    chaotic.push_back(c.chaotic);
    period.push_back(a.attractor.period ? *a.attractor.period : -1);
    impacts.push_back(a.attractor.impacts_per_period ? *a.attractor.impacts_per_period : -1);
    sp.push_back(a.attractor.sticking_fraction.value_or(nan));
    frac.push_back(a.basin_fraction);
    err.push_back(a.basin_fraction_error);
    kinds.push_back(a.attractor.kind);
    status.push_back(a.orbit.status);
    stable.push_back(a.orbit.stable ? (*a.orbit.stable ? 1 : 0) : -1);
    residual.push_back(a.orbit.residual);
    merged.push_back(a.orbit.merged);
    offset.push_back(static_cast<std::int32_t>(mu.size() / 2));
    count.push_back(static_cast<std::int32_t>(a.orbit.multipliers.size()));
    double l = a.orbit.multipliers.empty() ? nan : 0;
    for (const auto& z : a.orbit.multipliers) {
      mu.push_back(z.real());
      mu.push_back(z.imag());
      l = std::max(l, std::abs(z));
    }
    lead.push_back(l);
  }
  const h5::Size n = st.attractors.size();
  h5::WriteStrings(g, "kind", kinds);
  h5::WriteDataset(g, "period", h5::Type::I32(), period.data(), {n});
  h5::WriteDataset(g, "impacts_per_period", h5::Type::I64(), impacts.data(), {n});
  h5::WriteColumn(g, "sticking_fraction", sp);
  h5::WriteColumn(g, "basin_fraction", frac);
  h5::WriteColumn(g, "basin_fraction_error", err);
  // The Poincaré solver's orbit of each class (vibro extension).
  h5::WriteStrings(g, "orbit_status", status);
  h5::WriteDataset(g, "stable", h5::Type::I8(), stable.data(), {n});
  h5::WriteColumn(g, "orbit_residual", residual);
  h5::WriteDataset(g, "merged_classes", h5::Type::I32(), merged.data(), {n});
  h5::WriteDataset(g, "multiplier_count", h5::Type::I32(), count.data(), {n});
  h5::WriteDataset(g, "multiplier_offset", h5::Type::I32(), offset.data(), {n});
  h5::WriteDataset(g, "floquet_multipliers", h5::Type::F64(), mu.data(), {mu.size() / 2, 2});
  h5::WriteColumn(g, "leading_multiplier", lead);
  // The Lyapunov exponents of each attractor (vibro extension): the largest, its 95 % interval,
  // and chaotic (1 when the largest is positive beyond its interval, 0 when not, −1 no exponents).
  h5::WriteDataset(g, "lyapunov_max", h5::Type::F64(), lyap.data(), {n});
  h5::WriteDataset(g, "lyapunov_max_ci_low", h5::Type::F64(), lyap_lo.data(), {n});
  h5::WriteDataset(g, "lyapunov_max_ci_high", h5::Type::F64(), lyap_hi.data(), {n});
  h5::WriteDataset(g, "chaotic", h5::Type::I8(), chaotic.data(), {n});
  if (st.unresolved_lyapunov) {
    const store::LyapunovColumns u = store::LyapunovRow(st.unresolved_lyapunov);
    h5::WriteDouble(g, "unresolved_lyapunov_max", u.largest);
    h5::WriteInt(g, "unresolved_chaotic", u.chaotic);
  }
  h5::WriteInt(g, "rows", static_cast<long long>(n));
}

}  // namespace

void Hdf5Store::BeginStudy(const StudyGrid& grid) {
  auto& m = *impl_;
  m.Sync();
  const h5::Id f = m.file.get();
  m.basin = h5::CreateGroup(f, "/basin");
  const h5::Id b = m.basin.get();
  h5::WriteString(b, "x", grid.x.name);
  h5::WriteString(b, "y", grid.y.name);
  h5::WriteDoubles(b, "x_range", {grid.x.from, grid.x.to});
  h5::WriteDoubles(b, "y_range", {grid.y.from, grid.y.to});
  h5::WriteInt(b, "nx", grid.nx);
  h5::WriteInt(b, "ny", grid.ny);
  h5::WriteInt(b, "early_stop", grid.early_stop ? 1 : 0);
  m.cells_group = h5::CreateGroup(b, "cells");
  m.zcols = static_cast<h5::Size>(2 * m.header.dof);
  m.cells.emplace();
  m.cells->Create(m.cells_group.get(), m.zcols);
  m.Flush();
}

void Hdf5Store::WriteCells(const std::vector<size_t>& indices, const std::vector<CellResult>& cells) {
  auto& m = *impl_;
  for (size_t i : indices)
    if (cells[i].state != CellResult::State::kPending) m.cells->Push(i, cells[i], m.zcols);
  const auto now = std::chrono::steady_clock::now();
  if (std::chrono::duration<double>(now - m.last_flush).count() >= m.flush_interval) m.Flush();
}

std::unique_ptr<Hdf5Store> Hdf5Store::ResumeStudy(const std::string& path, const StoreHeader& h,
                                                  const StudyGrid& grid, std::vector<CellResult>& cells,
                                                  double flush_interval) {
  h5::Silence();
  // One writer per file: held from before the file is read until the resumed study closes it.
  store::FileLock lock = store::FileLock::Acquire(path, false);
  const StoredRun stored = ReadStoredRun(path);
  if (stored.scene_text != h.scene_text)
    throw InputError({fmt::format(
        "{}: cannot resume: the file holds a different scene (or different --set overrides) "
        "than the one given; resume with exactly the scene of the interrupted study",
        path)});
  if (stored.status == "ok")
    throw InputError({fmt::format("{}: nothing to resume: the study finished (status ok)", path)});
  // As in Resume: every change is made first on a copy (ProbeWrite).
  const auto prepare = [&](const std::string& file_path) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->header = h;
  impl->flush_interval = flush_interval;
  impl->zcols = static_cast<h5::Size>(2 * h.dof);
  std::vector<std::string> problems;
  try {
    impl->file = h5::OpenFile(file_path, true);
    if (!impl->file) throw std::runtime_error("cannot open the file for writing");
    const h5::Id f = impl->file.get();
    if (!h5::Exists(f, "/basin") || !h5::Exists(f, "/basin/cells"))
      throw InputError({fmt::format("{}: cannot resume: the file holds no basin study", path)});
    impl->basin = h5::OpenGroup(f, "/basin");
    const h5::Id b = impl->basin.get();
    // The same grid, or nothing.
    const auto same = [&](const std::string& what, const std::string& stored_value,
                          const std::string& given) {
      if (stored_value != given)
        problems.push_back(fmt::format("{}: cannot resume: {} is {} in the file but {} here", path, what,
                                       stored_value, given));
    };
    same("--x", h5::ReadString(b, "x"), grid.x.name);
    same("--y", h5::ReadString(b, "y"), grid.y.name);
    const auto range = [](const std::vector<double>& r) {
      return r.size() == 2 ? fmt::format("{},{}", r[0], r[1]) : std::string("?");
    };
    same("--x-range", range(h5::ReadDoubles(b, "x_range")), range({grid.x.from, grid.x.to}));
    same("--y-range", range(h5::ReadDoubles(b, "y_range")), range({grid.y.from, grid.y.to}));
    same("--grid",
         fmt::format("{},{}", h5::ReadInt(b, "nx").value_or(-1),
                     h5::ReadInt(b, "ny").value_or(-1)),
         fmt::format("{},{}", grid.nx, grid.ny));
    same("--full-periods",
         h5::ReadInt(b, "early_stop").value_or(1) ? "off" : "on",
         grid.early_stop ? "off" : "on");
    if (!problems.empty()) throw InputError(problems);
    // Everything is read and checked before anything is changed: a refused resume leaves the
    // file as it was.
    impl->cells_group = h5::OpenGroup(b, "cells");
    impl->cells.emplace();
    store::CellTable& t = *impl->cells;
    t.Open(impl->cells_group.get(), impl->zcols);
    h5::Size rows = t.index.rows();
    for (h5::Column* c : t.All())
      if (c != &t.phases) rows = std::min(rows, c->rows());
    const auto n = static_cast<size_t>(rows);
    std::vector<std::int64_t> index(n), impacts(n), periods(n);
    std::vector<std::int8_t> state(n), kind(n), stop(n);
    std::vector<std::int32_t> period(n), ns(n), ni(n);
    std::vector<double> sp(n), z(n * impl->zcols);
    t.index.Read(0, rows, index.data());
    t.state.Read(0, rows, state.data());
    t.kind.Read(0, rows, kind.data());
    t.period.Read(0, rows, period.data());
    t.impacts.Read(0, rows, impacts.data());
    t.sticking_fraction.Read(0, rows, sp.data());
    t.periods.Read(0, rows, periods.data());
    t.stop.Read(0, rows, stop.data());
    t.stick_count.Read(0, rows, ns.data());
    t.impact_count.Read(0, rows, ni.data());
    t.z.Read(0, rows, z.data());
    h5::Size values = 0;
    for (size_t i = 0; i < n; ++i) {
      // Each cell's fields in range (a flipped bit must not index past the tables).
      if (ns[i] < 0 || ni[i] < 0 || ns[i] > (1 << 20) || ni[i] > (1 << 20))
        throw std::runtime_error(fmt::format("cell row {}: phase counts {}, {} out of range", i, ns[i], ni[i]));
      if (state[i] < 0 || state[i] > 3 || kind[i] < 0 || kind[i] > 5 || periods[i] < 0 || period[i] < 0)
        throw std::runtime_error(fmt::format("cell row {}: state, kind or period out of range", i));
      if (index[i] < 0 || static_cast<size_t>(index[i]) >= cells.size())
        throw std::runtime_error("a cell index beyond the grid");
      if (!std::isnan(sp[i]) && !(sp[i] >= 0 && sp[i] <= 1))
        throw std::runtime_error(fmt::format("cell row {}: sticking fraction {} outside [0, 1]", i, sp[i]));
      values += static_cast<h5::Size>(2 * ns[i] + 2 * ni[i]);
    }
    if (values > t.phases.rows()) throw std::runtime_error("the cell table is incomplete");
    std::vector<double> ph(static_cast<size_t>(values));
    t.phases.Read(0, values, ph.data());
    const double* p = ph.data();
    const auto dof = static_cast<Eigen::Index>(h.dof);
    for (size_t i = 0; i < n; ++i) {
      if (index[i] < 0 || static_cast<size_t>(index[i]) >= cells.size())
        throw std::runtime_error("a cell index beyond the grid");
      CellResult c;
      c.state = static_cast<CellResult::State>(state[i]);
      c.attractor.kind = KindName(kind[i]);
      if (period[i] > 0) c.attractor.period = period[i];
      if (impacts[i] >= 0) c.attractor.impacts_per_period = impacts[i];
      if (!std::isnan(sp[i])) c.attractor.sticking_fraction = sp[i];
      c.periods = periods[i];
      c.stop = stop[i];
      for (int k = 0; k < ns[i]; ++k, p += 2) c.attractor.stick_phases.emplace_back(p[0], p[1]);
      c.attractor.impact_phases.assign(p, p + ni[i]);
      c.attractor.impact_velocities.assign(p + ni[i], p + 2 * ni[i]);
      p += 2 * ni[i];
      c.z = Eigen::Map<const Eigen::VectorXd>(z.data() + i * impl->zcols, 2 * dof);
      cells[static_cast<size_t>(index[i])] = std::move(c);
    }
    // Now the file changes, first its status (a file whose metadata cannot take a write fails
    // here, before anything else changed); then rows after the last complete batch are dropped,
    // and the label map and table of the interrupted run removed (written again at the end).
    h5::WriteString(f, "status", "running");
    h5::WriteString(f, "message", "");
    for (h5::Column* c : t.All()) c->Truncate(c == &t.phases ? values : rows);
    h5::DeleteLink(b, "labels");
    h5::DeleteLink(f, "/attractors");
    impl->OpenGroups();
    impl->OpenColumns();
    impl->Flush();
  } catch (const InputError&) {
    throw;
  } catch (const WriteError& e) {
    if (e.from_system()) throw;  // a full disk: exit 3, as during the run
    throw InputError({fmt::format("{}: cannot resume: {}", path, e.what())});
  } catch (const std::exception& e) {
    throw InputError({fmt::format("{}: cannot resume: {}", path, e.what())});
  }
  return impl;
  };
  // The trial on the copy (a child process) also writes what the resumed study writes later:
  // a batch of cells, the label map, the attractor table and the end. Damage that only those
  // writes meet is refused now, with the file unchanged.
  store::ProbeWrite(path, [&](const std::string& copy) {
    Hdf5Store store(prepare(copy));
    CellResult c;
    c.state = CellResult::State::kClassified;
    c.attractor.kind = "impact-periodic";
    c.attractor.period = 1;
    c.attractor.impacts_per_period = 1;
    c.attractor.impact_phases = {0.5};
    c.attractor.impact_velocities = {1.0};
    c.periods = 10;
    c.z = Eigen::VectorXd::Zero(2 * static_cast<Eigen::Index>(h.dof));
    const size_t n = cells.size();
    std::vector<size_t> batch;
    for (size_t i = 0; i < n && batch.size() < 4096; ++i) batch.push_back(i);
    store.WriteCells(batch, std::vector<CellResult>(batch.size(), c));
    StudyResult st;
    st.cells = static_cast<long long>(n);
    st.labels.assign(n, 0);
    FoundAttractor found;
    found.attractor = c.attractor;
    found.cells = st.cells;
    found.basin_fraction = 1;
    found.example = {grid.x.from, grid.y.from};
    st.attractors.push_back(found);
    store.WriteStudy(st, grid);
    RunResult r;
    r.status = RunStatus::kInterrupted;
    Attractor none;
    none.kind.clear();
    store.Finish(r, none);
  });
  auto impl = prepare(path);
  impl->lock = std::move(lock);
  impl->last_flush = std::chrono::steady_clock::now();
  return std::unique_ptr<Hdf5Store>(new Hdf5Store(std::move(impl)));
}

void Hdf5Store::WriteStudy(const StudyResult& st, const StudyGrid& grid) {
  auto& m = *impl_;
  m.Sync();
  const h5::Id f = m.file.get();
  if (!m.basin) {
    m.basin = h5::CreateGroup(f, "/basin");
    h5::WriteString(m.basin.get(), "x", grid.x.name);
    h5::WriteString(m.basin.get(), "y", grid.y.name);
    h5::WriteDoubles(m.basin.get(), "x_range", {grid.x.from, grid.x.to});
    h5::WriteDoubles(m.basin.get(), "y_range", {grid.y.from, grid.y.to});
    h5::WriteInt(m.basin.get(), "nx", grid.nx);
    h5::WriteInt(m.basin.get(), "ny", grid.ny);
    h5::WriteInt(m.basin.get(), "early_stop", grid.early_stop ? 1 : 0);
  }
  const h5::Id basin = m.basin.get();
  h5::DeleteLink(basin, "labels");
  h5::DeleteLink(f, "/attractors");
  const h5::Size dims[2] = {static_cast<h5::Size>(grid.ny), static_cast<h5::Size>(grid.nx)};
  static_assert(sizeof(st.labels[0]) == 4, "labels are int32");
  h5::WriteDataset(basin, "labels", h5::Type::I32(), st.labels.data(), {dims[0], dims[1]},
                   {std::min<h5::Size>(dims[0], 64), std::min<h5::Size>(dims[1], 512)});
  h5::WriteDouble(basin, "unresolved_fraction", st.unresolved_fraction);
  h5::WriteDouble(basin, "inadmissible_fraction", st.inadmissible_fraction);
  h5::WriteDouble(basin, "pending_fraction", st.pending_fraction);
  // /attractors: a table, one dataset per column, row k ↔ label k.
  WriteAttractorTable(f, st);
}

}  // namespace vibro
