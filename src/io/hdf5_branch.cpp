// Continuation branches in HDF5 (see include/vibro/hdf5_branch.hpp), through the store's
// generic tables (hdf5_table.cpp), and partitions (/partition: continuation columns in a
// parameter plane) through the HDF5 wrapper io/h5_file.hpp.
#include "vibro/hdf5_branch.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Rows of equal-length vectors as an (N, width) array; shorter rows NaN-padded.
H5Table::Array Rows(const std::string& name, const std::vector<const Eigen::VectorXd*>& rows) {
  size_t width = 0;
  for (const auto* r : rows) width = std::max(width, static_cast<size_t>(r->size()));
  H5Table::Array a{name, {rows.size(), width}, std::vector<double>(rows.size() * width, kNaN)};
  for (size_t i = 0; i < rows.size(); ++i)
    for (Eigen::Index j = 0; j < rows[i]->size(); ++j) a.data[i * width + static_cast<size_t>(j)] = (*rows[i])[j];
  return a;
}

}  // namespace

void Hdf5Store::WriteBranch(const Branch& b) {
  const size_t N = b.points.size();
  size_t m = 1, k = 1;
  for (const auto& pt : b.points) {
    m = std::max(m, pt.multipliers.size());
    k = std::max(k, pt.summary.stick_phases.size());
  }
  H5Table t;
  std::vector<double> value, sp, xb, phase, lead, stable, count, t0, offsets{0}, ip, ivb, iva;
  std::vector<double> mu(N * m * 2, kNaN), sticks(N * k * 2, kNaN);
  std::vector<std::string> events;
  std::vector<const Eigen::VectorXd*> X, V, q, qd;
  for (size_t i = 0; i < N; ++i) {
    const auto& pt = b.points[i];
    value.push_back(pt.value);
    sp.push_back(pt.summary.sticking_fraction.value_or(kNaN));
    xb.push_back(pt.x_B);
    phase.push_back(pt.section_phase);
    stable.push_back(pt.stable ? 1 : 0);
    events.push_back(pt.signature);
    double l = 0;
    for (size_t j = 0; j < pt.multipliers.size(); ++j) {
      l = std::max(l, std::abs(pt.multipliers[j]));
      mu[(i * m + j) * 2] = pt.multipliers[j].real();
      mu[(i * m + j) * 2 + 1] = pt.multipliers[j].imag();
    }
    lead.push_back(l);
    count.push_back(static_cast<double>(pt.summary.stick_phases.size()));
    for (size_t j = 0; j < pt.summary.stick_phases.size(); ++j) {
      sticks[(i * k + j) * 2] = pt.summary.stick_phases[j].first;
      sticks[(i * k + j) * 2 + 1] = pt.summary.stick_phases[j].second;
    }
    t0.push_back(pt.section_time);
    X.push_back(&pt.X);
    V.push_back(&pt.V);
    q.push_back(&pt.q);
    qd.push_back(&pt.q_dot);
    for (const auto& im : pt.impacts) {
      ip.push_back(im.phase);
      ivb.push_back(im.v_before);
      iva.push_back(im.v_after);
    }
    offsets.push_back(static_cast<double>(ip.size()));
  }
  const auto col = [&](const char* name, std::vector<double> v, char type = 'f') {
    const size_t rows = v.size();
    t.arrays.push_back({name, {rows}, std::move(v), type});
  };
  col("value", value);
  col("sticking_fraction", sp);
  col("x_B", xb);
  col("section_phase", phase);
  col("max_multiplier", lead);
  col("stable", stable, 'u');
  t.arrays.push_back({"multipliers", {N, m, 2}, mu});
  col("section_time", t0);
  t.arrays.push_back(Rows("X", X));
  t.arrays.push_back(Rows("V", V));
  if (N > 0 && b.points.front().q.size() > 0) {
    t.arrays.push_back(Rows("q", q));
    t.arrays.push_back(Rows("q_dot", qd));
  }
  t.arrays.push_back({"stick_phases", {N, k, 2}, sticks});
  col("stick_phase_count", count, 'i');
  col("impact_offsets", offsets, 'i');
  col("impact_phase", ip);
  col("impact_v_before", ivb);
  col("impact_v_after", iva);
  t.strings.emplace_back("events", events);
  t.text = {{"param", b.param}, {"end", b.end}, {"status", b.status}};
  t.integers = {{"period", b.period}, {"quad_evaluations", b.quad_evaluations}};
  WriteTable("/branch", t);

  H5Table bt;
  std::vector<double> bv, bb;
  std::vector<std::string> kind, detail;
  for (const auto& x : b.bifurcations) {
    bv.push_back(x.value);
    bb.push_back(x.bracket);
    kind.push_back(x.kind);
    detail.push_back(x.detail);
  }
  bt.arrays.push_back({"value", {bv.size()}, bv});
  bt.arrays.push_back({"bracket", {bb.size()}, bb});
  bt.strings = {{"kind", kind}, {"detail", detail}};
  WriteTable("/bifurcations", bt);

  // Signature changes that are no bifurcation (continuation.hpp, Relabel).
  H5Table rt;
  std::vector<double> rv, rb;
  std::vector<std::string> from, to, rdetail;
  for (const auto& x : b.relabels) {
    rv.push_back(x.value);
    rb.push_back(x.bracket);
    from.push_back(x.from);
    to.push_back(x.to);
    rdetail.push_back(x.detail);
  }
  rt.arrays.push_back({"value", {rv.size()}, rv});
  rt.arrays.push_back({"bracket", {rb.size()}, rb});
  rt.strings = {{"from", from}, {"to", to}, {"detail", rdetail}};
  WriteTable("/relabels", rt);
}

StoredBranchPoint ReadBranchPoint(const std::string& path, long long k) {
  const H5Table t = ReadTable(path, "/branch");
  const auto* value = t.Find("value");
  const auto* t0 = t.Find("section_time");
  const auto* X = t.Find("X");
  const auto* V = t.Find("V");
  if (!value || !t0 || !X || !V || X->dims.size() != 2)
    throw InputError({fmt::format("{}: /branch holds no orbit states (section_time, X, V): written by an "
                                  "older vibro; compute the branch again with vibro continue --out",
                                  path)});
  StoredBranchPoint p;
  p.points = static_cast<long long>(value->data.size());
  if (k < 0 || k >= p.points)
    throw InputError({fmt::format("--point {}: {} holds points 0 to {}", k, path, p.points - 1)});
  for (const auto& [name, text] : t.text)
    if (name == "param") p.param = text;
  for (const auto& [name, v] : t.integers)
    if (name == "period") p.period = static_cast<int>(v);
  const auto i = static_cast<size_t>(k);
  p.value = value->data[i];
  p.section_time = t0->data[i];
  const size_t n = X->dims[1];
  p.X = Eigen::Map<const Eigen::VectorXd>(X->data.data() + i * n, static_cast<Eigen::Index>(n));
  p.V = Eigen::Map<const Eigen::VectorXd>(V->data.data() + i * n, static_cast<Eigen::Index>(n));
  return p;
}

void Hdf5Store::WritePartition(const std::string& param1, const std::string& param2,
                               const std::vector<double>& levels,
                               const std::vector<PartitionColumn>& columns) {
  const h5::Handle g = h5::CreateGroup(impl_->file.get(), "/partition");
  h5::WriteString(g.get(), "param1", param1);
  h5::WriteString(g.get(), "param2", param2);
  h5::WriteDoubles(g.get(), "levels", levels);
  std::vector<double> cv, xv1, xl, xv2, bv1, bv2;
  std::vector<std::string> cs, bk;
  for (const auto& c : columns) {
    cv.push_back(c.value1);
    cs.push_back(c.status);
    for (const auto& x : c.crossings) {
      xv1.push_back(c.value1);
      xl.push_back(x.level);
      xv2.push_back(x.value);
    }
    for (const auto& b : c.bifurcations) {
      bv1.push_back(c.value1);
      bv2.push_back(b.value);
      bk.push_back(b.kind);
    }
  }
  h5::WriteColumn(g.get(), "column_value1", cv);
  h5::WriteStrings(g.get(), "column_status", cs);
  h5::WriteColumn(g.get(), "crossing_value1", xv1);
  h5::WriteColumn(g.get(), "crossing_level", xl);
  h5::WriteColumn(g.get(), "crossing_value2", xv2);
  h5::WriteColumn(g.get(), "boundary_value1", bv1);
  h5::WriteColumn(g.get(), "boundary_value2", bv2);
  h5::WriteStrings(g.get(), "boundary_kind", bk);
}

}  // namespace vibro
