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

// Per-row, per-contact loads (docs/loads.md) as a table of (rows, m) arrays, one per field of
// ContactLoads, m the most contacts of any row; a row without loads (or with fewer contacts) is
// NaN there. `note` holds each row's loads note.
H5Table LoadsTable(const std::vector<const std::vector<ContactLoads>*>& rows, const std::vector<std::string>& notes) {
  size_t m = 0;
  for (const auto* r : rows) m = std::max(m, r->size());
  using Field = double ContactLoads::*;
  const std::pair<const char*, Field> fields[] = {
      {"impacts_per_period", &ContactLoads::impacts_per_period},
      {"impulse_per_period", &ContactLoads::impulse_per_period},
      {"reaction_integral_per_period", &ContactLoads::reaction_integral_per_period},
      {"mean_force", &ContactLoads::mean_force},
      {"dissipated_power", &ContactLoads::dissipated_power},
      {"work_rate", &ContactLoads::work_rate},
      {"contact_fraction", &ContactLoads::contact_fraction}};
  H5Table t;
  for (const auto& [name, field] : fields) {
    H5Table::Array a{name, {rows.size(), m}, std::vector<double>(rows.size() * m, kNaN)};
    for (size_t i = 0; i < rows.size(); ++i)
      for (const ContactLoads& c : *rows[i])
        if (c.contact >= 0 && static_cast<size_t>(c.contact) < m) a.data[i * m + static_cast<size_t>(c.contact)] = c.*field;
    t.arrays.push_back(std::move(a));
  }
  t.strings.emplace_back("note", notes);
  t.integers = {{"contacts", static_cast<long long>(m)}};
  return t;
}

// A compliant stop's contact phases along a branch (docs/compliant.md, "Along a continued
// branch"; docs/output.md): per point and contact the largest peak force, the longest duration and
// the number of phases, (N, m); the rigid model's distance, (N); and every phase of every point, in
// flat columns, point i's phases at rows offsets[i] .. offsets[i+1] (as /branch/impact_*).
H5Table ContactPhasesTable(const Branch& b) {
  const size_t N = b.points.size();
  int m = 1;
  for (const auto& pt : b.points) {
    m = std::max(m, static_cast<int>(pt.loads.size()));
    for (const auto& p : pt.contact_phases) m = std::max(m, p.contact + 1);
  }
  const auto M = static_cast<size_t>(m);
  std::vector<double> peak(N * M, kNaN), duration(N * M, kNaN), count(N * M, 0), rigid, offsets{0};
  std::vector<double> contact, entry, exit, dur, vin, vout, force, tpeak, pen, impulse, energy;
  for (size_t i = 0; i < N; ++i) {
    const auto& pt = b.points[i];
    const ContactPhaseExtremes e = ExtremesOf(pt.contact_phases, m);
    for (size_t j = 0; j < M; ++j) {
      peak[i * M + j] = e.peak_force[j];
      duration[i * M + j] = e.duration[j];
      count[i * M + j] = e.phases[j];
    }
    rigid.push_back(pt.rigid_distance);
    for (const auto& p : pt.contact_phases) {
      contact.push_back(p.contact);
      entry.push_back(p.entry);
      exit.push_back(p.exit);
      dur.push_back(p.duration);
      vin.push_back(p.entry_velocity);
      vout.push_back(p.exit_velocity);
      force.push_back(p.peak_force);
      tpeak.push_back(p.peak_time);
      pen.push_back(p.penetration);
      impulse.push_back(p.impulse);
      energy.push_back(p.dissipated);
    }
    offsets.push_back(static_cast<double>(contact.size()));
  }
  H5Table t;
  t.arrays.push_back({"peak_force", {N, M}, peak});
  t.arrays.push_back({"duration", {N, M}, duration});
  t.arrays.push_back({"phases", {N, M}, count, 'i'});
  t.arrays.push_back({"rigid_distance", {N}, rigid});
  t.arrays.push_back({"offsets", {N + 1}, offsets, 'i'});
  const auto col = [&](const char* name, std::vector<double> v, char type = 'f') {
    const size_t rows = v.size();
    t.arrays.push_back({name, {rows}, std::move(v), type});
  };
  col("phase_contact", contact, 'i');
  col("phase_entry", entry);
  col("phase_exit", exit);
  col("phase_duration", dur);
  col("phase_entry_velocity", vin);
  col("phase_exit_velocity", vout);
  col("phase_peak_force", force);
  col("phase_peak_time", tpeak);
  col("phase_penetration", pen);
  col("phase_impulse", impulse);
  col("phase_energy_dissipated", energy);
  t.integers = {{"contacts", static_cast<long long>(m)}};
  return t;
}

}  // namespace

void Hdf5Store::WriteBranch(const Branch& b, const std::string& group) {
  impl_->Sync();
  const size_t N = b.points.size();
  size_t m = 1, k = 1;
  for (const auto& pt : b.points) {
    m = std::max(m, pt.multipliers.size());
    k = std::max(k, pt.summary.stick_phases.size());
  }
  H5Table t;
  std::vector<double> value, sp, xb, phase, lead, stable, count, t0, offsets{0}, ip, ivb, iva;
  std::vector<double> mu(N * m * 2, kNaN), sticks(N * k * 2, kNaN), stick_contacts(N * k, -1);
  size_t contacts = 1;  // the stroboscopic state: (N, contacts), NaN where not simulated
  for (const auto& pt : b.points) contacts = std::max(contacts, pt.strobe.size());
  std::vector<double> strobe(N * contacts, kNaN);
  std::vector<std::string> events, sequence;
  std::vector<double> icontact;
  std::vector<const Eigen::VectorXd*> X, V, q, qd;
  for (size_t i = 0; i < N; ++i) {
    const auto& pt = b.points[i];
    value.push_back(pt.value);
    sp.push_back(pt.summary.sticking_fraction.value_or(kNaN));
    xb.push_back(pt.x_B);
    phase.push_back(pt.section_phase);
    for (size_t j = 0; j < pt.strobe.size(); ++j) strobe[i * contacts + j] = pt.strobe[j];
    stable.push_back(pt.stable ? 1 : 0);
    events.push_back(pt.signature);
    sequence.push_back(pt.sequence);
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
      // The contact each phase sticks on (docs/output.md); -1 pads, as NaN pads the phases.
      if (j < pt.summary.stick_contacts.size())
        stick_contacts[i * k + j] = static_cast<double>(pt.summary.stick_contacts[j]);
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
      icontact.push_back(im.contact);
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
  t.arrays.push_back({"strobe", {N, contacts}, strobe});
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
  t.arrays.push_back({"stick_contacts", {N, k}, stick_contacts, 'i'});
  col("stick_phase_count", count, 'i');
  col("impact_offsets", offsets, 'i');
  col("impact_phase", ip);
  col("impact_v_before", ivb);
  col("impact_v_after", iva);
  col("impact_contact", icontact, 'i');
  t.strings.emplace_back("events", events);
  t.strings.emplace_back("sequence", sequence);
  t.text = {{"param", b.param}, {"end", b.end}, {"status", b.status}};
  t.integers = {{"period", b.period}, {"quad_evaluations", b.quad_evaluations}, {"closed_loop", b.closed_loop ? 1 : 0}};
  WriteTable(group + "/branch", t);
  std::vector<const std::vector<ContactLoads>*> loads;
  std::vector<std::string> notes;
  for (const auto& pt : b.points) {
    loads.push_back(&pt.loads);
    notes.push_back(pt.loads_note);
  }
  WriteTable(group + "/branch/loads", LoadsTable(loads, notes));
  if (std::any_of(b.points.begin(), b.points.end(), [](const BranchPoint& pt) { return !pt.contact_phases.empty(); }))
    WriteTable(group + "/branch/contact_phases", ContactPhasesTable(b));

  H5Table bt;
  std::vector<double> bv, bb, bc, rot, nv, nd, bp;
  std::vector<std::string> kind, detail, ev0, ev1, sq0, sq1, through;
  for (const auto& x : b.bifurcations) {
    ev0.push_back(x.events_before);
    ev1.push_back(x.events_after);
    sq0.push_back(x.sequence_before);
    sq1.push_back(x.sequence_after);
    through.push_back(x.through);
    nv.push_back(x.new_impact_speed);
    nd.push_back(x.new_impact_distance);
    rot.push_back(x.rotation_number);
    bv.push_back(x.value);
    bb.push_back(x.bracket);
    bc.push_back(x.contact);
    bp.push_back(static_cast<double>(x.point));
    kind.push_back(x.kind);
    detail.push_back(x.detail);
  }
  bt.arrays.push_back({"value", {bv.size()}, bv});
  bt.arrays.push_back({"bracket", {bb.size()}, bb});
  bt.arrays.push_back({"contact", {bc.size()}, bc, 'i'});
  bt.arrays.push_back({"point", {bp.size()}, bp, 'i'});  // the branch's point before it (−1: unknown)
  bt.arrays.push_back({"rotation_number", {rot.size()}, rot});  // Neimark–Sacker points; NaN elsewhere
  // Non-smooth points (continuation.hpp, Bifurcation): events and contact sequences before and
  // past the point (empty: none, or a smooth kind), how the branch went through it ("past",
  // "back", empty: it ended), and at a grazing it went through, the new impact's speed and
  // distance at the first point past it (NaN elsewhere).
  bt.arrays.push_back({"new_impact_speed", {nv.size()}, nv});
  bt.arrays.push_back({"new_impact_distance", {nd.size()}, nd});
  bt.strings = {{"kind", kind},          {"detail", detail},         {"events_before", ev0},
                {"events_after", ev1},   {"sequence_before", sq0},   {"sequence_after", sq1},
                {"through", through}};
  WriteTable(group + "/bifurcations", bt);

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
  WriteTable(group + "/relabels", rt);
}

StoredBranchPoint ReadBranchPoint(const std::string& path, long long k) {
  h5::Silence();
  // Only what a restart needs is read (never the event strings): first in a child, which a
  // damaged file may crash without harm, then here, row k alone, every value checked. Every object
  // read below is in the child's list: /branch/sequence (the contact sequences of several contacts)
  // was not, and a damaged heap of its strings crashed vibro itself.
  const std::vector<std::string> needed{"/branch", "/branch/value", "/branch/section_time", "/branch/X",
                                        "/branch/V", "/branch/sequence"};
  store::ProbeInChild(path, needed);
  const h5::Handle file = h5::OpenFile(path, false);
  if (!file) throw store::CannotOpen(path);
  const auto bad = [&](const std::string& what, const std::string& expected) {
    return InputError({fmt::format("{}: {}: expected {}", path, what, expected)});
  };
  const h5::Handle g = h5::TryOpenGroup(file.get(), "/branch");
  if (!g) throw InputError({fmt::format("{}: no group /branch in this file (not a continuation branch)", path)});
  for (const char* name : {"section_time", "X", "V"})
    if (!h5::DatasetShape(g.get(), name))
      throw InputError({fmt::format("{}: /branch holds no orbit states (section_time, X, V): written by an "
                                    "older vibro; compute the branch again with vibro continue --out",
                                    path)});
  // Shapes and types before anything is read: N points (value, section_time) and (N, n) states.
  constexpr h5::Size kMaxPoints = h5::Size{1} << 24;  // continue --max-points at most
  constexpr h5::Size kMaxModes = 4096;
  for (const char* name : {"value", "section_time", "X", "V"}) {
    const h5::Class c = h5::DatasetClass(g.get(), name);
    if (c != h5::Class::kFloat && c != h5::Class::kInteger)
      throw bad(fmt::format("/branch/{}", name), "a numeric dataset (float64)");
  }
  const auto value = *h5::DatasetShape(g.get(), "value");
  if (value.size() != 1 || value[0] == 0 || value[0] > kMaxPoints)
    throw bad("/branch/value", fmt::format("one dimension of 1 to {} points", kMaxPoints));
  const h5::Size n_points = value[0];
  if (*h5::DatasetShape(g.get(), "section_time") != std::vector<h5::Size>{n_points})
    throw bad("/branch/section_time", fmt::format("shape ({}), as /branch/value", n_points));
  const auto X = *h5::DatasetShape(g.get(), "X");
  if (X.size() != 2 || X[0] != n_points || X[1] == 0 || X[1] > kMaxModes)
    throw bad("/branch/X", fmt::format("shape ({}, n) with 1 ≤ n ≤ {} (a row per point of /branch/value)",
                                       n_points, kMaxModes));
  if (*h5::DatasetShape(g.get(), "V") != X)
    throw bad("/branch/V", fmt::format("shape ({}, {}), as /branch/X", X[0], X[1]));
  // Attributes: the parameter's name and the period, in range.
  if (h5::AttrClass(g.get(), "param") != h5::Class::kString)
    throw bad("/branch attribute param", "a string (the scene key the branch varies)");
  if (h5::AttrClass(g.get(), "period") != h5::Class::kInteger)
    throw bad("/branch attribute period", "an integer 1 to 4096");
  StoredBranchPoint p;
  p.points = static_cast<long long>(n_points);
  if (k < 0 || k >= p.points)
    throw InputError({fmt::format("--point {}: {} holds points 0 to {}", k, path, p.points - 1)});
  try {
    p.param = h5::ReadString(g.get(), "param");
    const auto period = h5::ReadInt(g.get(), "period");
    if (!period || *period < 1 || *period > 4096)
      throw bad("/branch attribute period", fmt::format("an integer 1 to 4096, found {}", period.value_or(0)));
    p.period = static_cast<int>(*period);
    const auto row = static_cast<h5::Size>(k);
    p.value = h5::ReadDatasetRow(g.get(), "value", row)[0];
    p.section_time = h5::ReadDatasetRow(g.get(), "section_time", row)[0];
    const auto x = h5::ReadDatasetRow(g.get(), "X", row), v = h5::ReadDatasetRow(g.get(), "V", row);
    p.X = Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size()));
    p.V = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
    if (h5::Exists(g.get(), "sequence")) {
      if (!h5::IsStringDataset(g.get(), "sequence")) throw bad("/branch/sequence", "a dataset of strings");
      const auto sequences = h5::ReadDatasetStrings(g.get(), "sequence");
      if (sequences.size() != n_points)
        throw bad("/branch/sequence", fmt::format("one entry per point ({}), found {}", n_points, sequences.size()));
      p.sequence = sequences[static_cast<size_t>(k)];
    }
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError({fmt::format("{}: /branch point {} cannot be read: {}", path, k, e.what())});
  }
  const auto finite = [&](const std::string& what, double x) {
    if (!std::isfinite(x)) throw bad(fmt::format("{} of point {}", what, k), fmt::format("a finite number, found {}", x));
  };
  finite("/branch/value", p.value);
  finite("/branch/section_time", p.section_time);
  for (Eigen::Index i = 0; i < p.X.size(); ++i) {
    finite(fmt::format("/branch/X[{}]", i), p.X[i]);
    finite(fmt::format("/branch/V[{}]", i), p.V[i]);
  }
  return p;
}

void Hdf5Store::WritePartition(const std::string& param1, const std::string& param2,
                               const std::vector<double>& levels,
                               const std::vector<PartitionColumn>& columns) {
  impl_->Sync();
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
  // The cells: every branch point of every column, with its loads in /partition/loads.
  std::vector<double> pv1, pv2, psp, pst, pcol;
  std::vector<const std::vector<ContactLoads>*> loads;
  std::vector<std::string> notes;
  for (size_t i = 0; i < columns.size(); ++i)
    for (const auto& pt : columns[i].points) {
      pcol.push_back(static_cast<double>(i));
      pv1.push_back(columns[i].value1);
      pv2.push_back(pt.value2);
      psp.push_back(pt.sticking_fraction);
      pst.push_back(pt.stable ? 1 : 0);
      loads.push_back(&pt.loads);
      notes.push_back(pt.loads_note);
    }
  H5Table cells = LoadsTable(loads, notes);
  const auto col = [&](const char* name, std::vector<double> v, char type = 'f') {
    const size_t rows = v.size();
    cells.arrays.push_back({name, {rows}, std::move(v), type});
  };
  col("column", pcol, 'i');
  col("value1", pv1);
  col("value2", pv2);
  col("sticking_fraction", psp);
  col("stable", pst, 'u');
  WriteTable("/partition/points", cells);
  // Several contacts: the spans of one contact sequence per column (PartitionColumn::sequences).
  std::vector<double> sv1, sfrom, sto;
  std::vector<std::string> stext;
  for (const auto& c : columns)
    for (const auto& sp : c.sequences) {
      sv1.push_back(c.value1);
      sfrom.push_back(sp.from);
      sto.push_back(sp.to);
      stext.push_back(sp.sequence);
    }
  if (!stext.empty()) {
    h5::WriteColumn(g.get(), "sequence_value1", sv1);
    h5::WriteColumn(g.get(), "sequence_from", sfrom);
    h5::WriteColumn(g.get(), "sequence_to", sto);
    h5::WriteStrings(g.get(), "sequence", stext);
  }
}

StoredBranchPoint NearestBranchPoint(const std::string& path, double value, double apart, long long before) {
  // The branch's point before the bifurcation, or the first one back from it at least `apart` from
  // it (a branch through a grazing or round a loop passes the same λ on other orbits).
  if (before >= 0) {
    const auto last = ReadBranchPoint(path, 0);
    if (before < last.points) {
      for (long long k = before; k >= 0; --k) {
        auto p = ReadBranchPoint(path, k);
        if (std::abs(p.value - value) >= apart || k == 0) return p;
      }
    }
  }
  const auto distance = [&](double v) { return std::abs(v - value) >= apart ? std::abs(v - value) : 1e300 + std::abs(v - value); };
  StoredBranchPoint near = ReadBranchPoint(path, 0);
  for (long long k = 1; k < near.points; ++k) {
    auto p = ReadBranchPoint(path, k);
    if (distance(p.value) < distance(near.value)) near = std::move(p);
  }
  return near;
}

std::vector<Bifurcation> ReadBranchBifurcations(const std::string& path) {
  h5::Silence();
  // The child reads every object read below: a group's probe reads its attributes only, and the
  // strings of /bifurcations/kind were read here untried (a damaged heap of them would crash vibro).
  store::ProbeInChild(path, {"/bifurcations", "/bifurcations/value", "/bifurcations/kind", "/bifurcations/bracket"});
  const h5::Handle file = h5::OpenFile(path, false);
  if (!file) throw store::CannotOpen(path);
  const h5::Handle g = h5::TryOpenGroup(file.get(), "/bifurcations");
  if (!g) throw InputError({fmt::format("{}: no group /bifurcations in this file (not a continuation branch)", path)});
  const auto bad = [&](const std::string& what, const std::string& expected) {
    return InputError({fmt::format("{}: /bifurcations/{}: expected {}", path, what, expected)});
  };
  if (!h5::DatasetShape(g.get(), "value") || h5::DatasetClass(g.get(), "value") != h5::Class::kFloat)
    throw bad("value", "a float64 dataset");
  if (!h5::IsStringDataset(g.get(), "kind")) throw bad("kind", "a dataset of strings");
  std::vector<double> value, bracket, point;
  std::vector<std::string> kind;
  try {
    value = h5::ReadDatasetDoubles(g.get(), "value");
    kind = h5::ReadDatasetStrings(g.get(), "kind");
    if (h5::DatasetShape(g.get(), "bracket")) bracket = h5::ReadDatasetDoubles(g.get(), "bracket");
    if (h5::DatasetShape(g.get(), "point")) point = h5::ReadDatasetDoubles(g.get(), "point");
  } catch (const std::exception& e) {
    throw InputError({fmt::format("{}: /bifurcations cannot be read: {}", path, e.what())});
  }
  if (kind.size() != value.size()) throw bad("kind", fmt::format("one entry per value ({}), found {}", value.size(), kind.size()));
  std::vector<Bifurcation> out;
  for (size_t i = 0; i < value.size(); ++i) {
    if (!std::isfinite(value[i])) throw bad(fmt::format("value[{}]", i), fmt::format("a finite number, found {}", value[i]));
    out.push_back({kind[i], value[i], "", i < bracket.size() ? bracket[i] : 0.0});
    if (i < point.size() && std::isfinite(point[i]) && point[i] >= 0) out.back().point = static_cast<long long>(point[i]);
  }
  return out;
}

long long BifurcationPointNear(const std::string& path, const std::string& kind, double value, double within) {
  long long point = -1;
  double best = within;
  std::vector<Bifurcation> list;
  try {
    list = ReadBranchBifurcations(path);
  } catch (const InputError&) {
    return -1;  // not a branch with bifurcations: NearestBranchPoint says what the file is
  }
  for (const auto& b : list)
    if (b.kind == kind && b.point >= 0 && std::abs(b.value - value) <= best) {
      best = std::abs(b.value - value);
      point = b.point;
    }
  return point;
}

}  // namespace vibro
