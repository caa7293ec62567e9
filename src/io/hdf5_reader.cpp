// Reading a stored run back (vibro info, resume, tests): the root's attributes, the row counts,
// the checkpoint (every value checked before a resume starts from it), the tail of events and
// section points a resume reloads, the attractor and a line per result group.
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"
#include "vibro/hdf5_store.hpp"
#include "vibro/scene_file.hpp"

namespace vibro {
namespace {

// What a result group holds, in a line: its rows and main attributes.
std::string DescribeGroup(h5::Id f, const std::string& name) {
  const h5::Handle g = h5::TryOpenGroup(f, name);
  if (!g) return "";
  std::vector<std::string> parts;
  for (const char* d : {"value", "labels", "t", "kind", "value1", "index"}) {
    const auto dims = h5::DatasetShape(g.get(), d);
    if (!dims) continue;
    const h5::Size rows = dims->empty() ? 0 : (*dims)[0];
    parts.push_back(dims->size() == 2 && std::string(d) == "labels"
                        ? fmt::format("{} × {} cells", (*dims)[1], (*dims)[0])
                        : fmt::format("{} rows", rows));
    break;
  }
  for (const char* k : {"param", "param1", "param2", "x", "y", "period", "stable", "residual", "end", "status",
                        "unresolved_fraction"}) {
    if (!h5::HasAttr(g.get(), k)) continue;
    const auto text = h5::AttrText(g.get(), k);
    if (!text.empty()) parts.push_back(fmt::format("{} = {}", k, text));
  }
  std::string line;
  for (const auto& p : parts) line += (line.empty() ? "" : ", ") + p;
  return line;
}

}  // namespace

StoredRun ReadStoredRun(const std::string& path, int tail_periods) {
  h5::Silence();
  store::ProbeInChild(path);
  StoredRun out;
  const h5::Handle file = h5::OpenFile(path, false);
  if (!file) throw store::CannotOpen(path);
  const h5::Id f = file.get();
  if (!h5::HasAttr(f, "vibro_version"))
    throw InputError({fmt::format("{}: not a vibro output file (no vibro_version attribute)", path)});
  try {
    out.version = h5::ReadString(f, "vibro_version");
    out.scene_text = h5::ReadString(f, "scene");
    out.engine = h5::ReadString(f, "engine");
    out.chatter = h5::ReadString(f, "chatter");
    out.status = h5::ReadString(f, "status");
    out.message = h5::ReadString(f, "message");
    out.created = h5::ReadString(f, "created");
    const h5::Handle ev = h5::OpenGroup(f, "/events");
    const h5::Handle sa = h5::OpenGroup(f, "/samples");
    const h5::Handle se = h5::OpenGroup(f, "/section");
    store::EventTable events;
    store::StateTable samples, sections;
    events.Open(ev.get());
    samples.Open(sa.get(), h5::Column::kAnyCols);
    sections.Open(se.get(), h5::Column::kAnyCols);
    out.events = static_cast<long long>(events.t.rows());
    out.samples = static_cast<long long>(samples.t.rows());
    out.sections = static_cast<long long>(sections.t.rows());

    const h5::Handle cpg = h5::OpenGroup(f, "/checkpoint");
    const h5::Id g = cpg.get();
    h5::Size cp_events = events.t.rows(), cp_sections = sections.t.rows();
    if (auto period = h5::ReadInt(g, "period")) {
      Checkpoint c{};
      c.clock = {*period, *h5::ReadDouble(g, "offset")};
      const auto X = h5::ReadDoubles(g, "X"), V = h5::ReadDoubles(g, "V");
      // Every value of the checkpoint in its range before it is used (a resume starts from it).
      const auto bad = [](const std::string& what) {
        throw std::runtime_error("checkpoint " + what + " out of range");
      };
      if (*period < 0 || !std::isfinite(c.clock.offset) || c.clock.offset < 0) bad("period/offset");
      if (X.empty() || X.size() != V.size() || X.size() != sections.X.cols() ||
          V.size() != sections.V.cols() || samples.X.cols() != X.size() || samples.V.cols() != X.size())
        bad("X/V (their length must be the width of /section/X, /section/V, /samples/X, /samples/V)");
      for (double x : X) if (!std::isfinite(x)) bad("X");
      for (double x : V) if (!std::isfinite(x)) bad("V");
      c.X = Eigen::Map<const Eigen::VectorXd>(X.data(), static_cast<Eigen::Index>(X.size()));
      c.V = Eigen::Map<const Eigen::VectorXd>(V.data(), static_cast<Eigen::Index>(V.size()));
      c.mode = static_cast<Mode>(*h5::ReadInt(g, "mode"));
      c.gap = *h5::ReadDouble(g, "gap");
      c.start_kind = static_cast<int>(*h5::ReadInt(g, "start_kind"));
      c.chatter_first_speed = *h5::ReadDouble(g, "chatter_first_speed");
      c.chatter_last_speed = *h5::ReadDouble(g, "chatter_last_speed");
      c.sample_index = *h5::ReadInt(g, "sample_index");
      c.counts.impacts = *h5::ReadInt(g, "impacts");
      c.counts.accumulations = *h5::ReadInt(g, "accumulations");
      c.counts.sticks = *h5::ReadInt(g, "sticks");
      c.counts.releases = *h5::ReadInt(g, "releases");
      c.counts.grazings = *h5::ReadInt(g, "grazings");
      // Absent in files written before the checkpoint carried them (0: counted from the resume).
      c.chatter_predicted = h5::ReadInt(g, "chatter_accumulations_predicted").value_or(0);
      c.chatter_followed = h5::ReadInt(g, "chatter_impacts_followed").value_or(0);
      c.chatter_max_error = h5::ReadDouble(g, "chatter_max_estimated_error").value_or(0.0);
      if (c.chatter_predicted < 0 || c.chatter_followed < 0 || !std::isfinite(c.chatter_max_error) ||
          c.chatter_max_error < 0)
        bad("chatter counts");
      // Several contacts (absent for one contact): the held or start contact, gaps, starts, counts.
      if (auto k = h5::ReadInt(g, "contact")) {
        c.contact = static_cast<int>(*k);
        c.gaps = h5::ReadDoubles(g, "gaps");
        const auto starts = h5::ReadDoubles(g, "start_kinds");
        const auto counts = h5::ReadDoubles(g, "contact_counts");
        const size_t m = c.gaps.size();
        if (m < 2 || m > 1024 || *k < 0 || static_cast<size_t>(*k) >= m || starts.size() != m ||
            counts.size() != 6 * m)
          bad("contact, gaps, start_kinds, contact_counts (one per contact)");
        for (double x : c.gaps)
          if (!std::isfinite(x)) bad("gaps");
        for (double x : starts) {
          if (!(x >= 0 && x <= 8) || x != std::floor(x)) bad("start_kinds");
          c.start_kinds.push_back(static_cast<int>(x));
        }
        for (double x : counts)
          if (!(x >= 0 && x <= 9.0e15) || x != std::floor(x)) bad("contact_counts");
        for (size_t j = 0; j < m; ++j) {
          const double* r = counts.data() + 6 * j;
          c.contact_counts.push_back({static_cast<long long>(r[0]), static_cast<long long>(r[1]),
                                      static_cast<long long>(r[2]), static_cast<long long>(r[3]),
                                      static_cast<long long>(r[4]), static_cast<long long>(r[5])});
        }
        // Sticking on two or more contacts at once (absent otherwise): the held contacts.
        for (double x : h5::ReadDoubles(g, "held")) {
          if (!(x >= 0 && x < static_cast<double>(m)) || x != std::floor(x)) bad("held");
          c.held.push_back(static_cast<int>(x));
        }
        if (c.held.size() == 1 || c.held.size() > m) bad("held");
      }
      // The open sticking phases (docs/loads.md); absent in files written before them.
      c.stick_duration = h5::ReadDoubles(g, "stick_duration");
      c.reaction_integral = h5::ReadDoubles(g, "reaction_integral");
      c.reaction_max = h5::ReadDoubles(g, "reaction_max");
      if (c.reaction_integral.size() != c.stick_duration.size() ||
          c.reaction_max.size() != c.stick_duration.size())
        bad("stick_duration, reaction_integral, reaction_max (one per contact)");
      // Compliant stops (docs/compliant.md): absent in files written before them, and for rigid scenes.
      c.compliant_account = h5::ReadDoubles(g, "compliant_account");
      if (!c.compliant_account.empty()) {
        const auto relax = h5::ReadInt(g, "relax_contact");
        const std::vector<double> surface = h5::ReadDoubles(g, "relax_surface");
        if (c.compliant_account.size() % 4 != 0 || !relax || surface.size() != 1 || !std::isfinite(surface[0]) ||
            *relax < -1 || *relax >= static_cast<long long>(c.compliant_account.size() / 4))
          bad("compliant_account, relax_contact, relax_surface");
        c.relax_contact = static_cast<int>(*relax);
        c.relax_surface = surface[0];
      }
      cp_events = static_cast<h5::Size>(*h5::ReadInt(g, "events"));
      cp_sections = static_cast<h5::Size>(*h5::ReadInt(g, "sections"));
      const auto cp_samples = *h5::ReadInt(g, "samples");
      if (static_cast<int>(c.mode) != 0 && static_cast<int>(c.mode) != 1) bad("mode");
      if (c.start_kind < 0 || c.start_kind > 8 || !std::isfinite(c.gap)) bad("start");
      if (!std::isfinite(c.chatter_first_speed) || !std::isfinite(c.chatter_last_speed)) bad("chatter speeds");
      if (c.sample_index < 0 || c.counts.impacts < 0 || c.counts.accumulations < 0 || c.counts.sticks < 0 ||
          c.counts.releases < 0 || c.counts.grazings < 0)
        bad("counts");
      if (cp_events > events.t.rows() || cp_sections > sections.t.rows() || cp_samples < 0 ||
          static_cast<h5::Size>(cp_samples) > samples.t.rows())
        bad("row counts (more rows than the tables hold)");
      for (h5::Column* col : events.All())
        if (col->rows() < cp_events) bad("events (a column of /events is short)");
      for (h5::Column* col : sections.All())
        if (col->rows() < cp_sections) bad("sections (a column of /section is short)");
      for (h5::Column* col : samples.All())
        if (col->rows() < static_cast<h5::Size>(cp_samples)) bad("samples (a column of /samples is short)");
      out.checkpoint = c;
    }

    if (tail_periods > 0 && out.checkpoint) {
      const long long from = out.checkpoint->clock.period - tail_periods;
      // Sections: one row per period, the last tail_periods + 1 before the checkpoint.
      const h5::Size n_se = std::min<h5::Size>(cp_sections, static_cast<h5::Size>(tail_periods + 1));
      const h5::Size first = cp_sections - n_se;
      const auto dof = static_cast<size_t>(out.checkpoint->X.size());
      std::vector<std::int64_t> per(n_se);
      std::vector<double> X(n_se * dof), V(n_se * dof);
      std::vector<std::int8_t> mode(n_se);
      sections.period.Read(first, n_se, per.data());
      sections.X.Read(first, n_se, X.data());
      sections.V.Read(first, n_se, V.data());
      sections.mode.Read(first, n_se, mode.data());
      for (h5::Size i = 0; i < n_se; ++i) {
        out.tail_section_clocks.push_back({per[i], 0.0});
        out.tail_section_X.emplace_back(Eigen::Map<Eigen::VectorXd>(X.data() + i * dof, static_cast<Eigen::Index>(dof)));
        out.tail_section_V.emplace_back(Eigen::Map<Eigen::VectorXd>(V.data() + i * dof, static_cast<Eigen::Index>(dof)));
        out.tail_section_modes.push_back(static_cast<Mode>(mode[i]));
      }
      // Events: read backwards in blocks until before `from`.
      h5::Size first_ev = cp_events;
      std::vector<std::int64_t> block;
      while (first_ev > 0) {
        const h5::Size n = std::min<h5::Size>(first_ev, 65536);
        block.resize(n);
        events.period.Read(first_ev - n, n, block.data());
        first_ev -= n;
        if (block.front() < from) {
          h5::Size skip = 0;
          while (skip < n && block[skip] < from) ++skip;
          first_ev += skip;
          break;
        }
      }
      const h5::Size n_ev = cp_events - first_ev;
      std::vector<double> t(n_ev), off(n_ev), xB(n_ev), vb(n_ev), va(n_ev);
      std::vector<std::int64_t> ep(n_ev);
      std::vector<std::int8_t> kind(n_ev);
      events.offset.Read(first_ev, n_ev, off.data());
      events.t.Read(first_ev, n_ev, t.data());
      events.period.Read(first_ev, n_ev, ep.data());
      events.kind.Read(first_ev, n_ev, kind.data());
      events.xB.Read(first_ev, n_ev, xB.data());
      events.v_before.Read(first_ev, n_ev, vb.data());
      events.v_after.Read(first_ev, n_ev, va.data());
      std::vector<std::int32_t> contact(n_ev, 0);
      std::vector<std::int8_t> simultaneous(n_ev, 0);
      if (events.has_contact) {
        events.contact.Read(first_ev, n_ev, contact.data());
        events.simultaneous.Read(first_ev, n_ev, simultaneous.data());
      }
      const double nan = std::numeric_limits<double>::quiet_NaN();
      std::vector<double> imp(n_ev, 0.0), en(n_ev, 0.0), sd(n_ev, nan), ri(n_ev, nan), rm(n_ev, nan);
      if (events.has_loads) {
        events.impulse.Read(first_ev, n_ev, imp.data());
        events.energy.Read(first_ev, n_ev, en.data());
        events.stick_duration.Read(first_ev, n_ev, sd.data());
        events.reaction_integral.Read(first_ev, n_ev, ri.data());
        events.reaction_max.Read(first_ev, n_ev, rm.data());
      }
      std::vector<double> pt(n_ev, nan), pm(n_ev, nan);  // a compliant contact phase's (docs/compliant.md)
      if (events.has_compliant) {
        events.peak_time.Read(first_ev, n_ev, pt.data());
        events.penetration_max.Read(first_ev, n_ev, pm.data());
      }
      for (h5::Size i = 0; i < n_ev; ++i) {
        out.tail_events.push_back({static_cast<EventKind>(kind[i]), {ep[i], off[i]}, t[i], xB[i], vb[i], va[i],
                                   contact[i], simultaneous[i] != 0, imp[i], en[i], sd[i], ri[i], rm[i]});
        out.tail_events.back().peak_time = pt[i];
        out.tail_events.back().penetration_max = pm[i];
      }
    }

    // Studies and branches (and their files since provenance was stored) have no /attractor.
    out.attractor.kind.clear();
    if (h5::Exists(f, "/attractor")) {
      const h5::Handle ag = h5::OpenGroup(f, "/attractor");
      out.attractor.kind = h5::ReadString(ag.get(), "kind");
      if (auto p = h5::ReadInt(ag.get(), "period")) {
        if (*p < 1 || *p > (1 << 20)) throw std::runtime_error(fmt::format("/attractor period {} out of range", *p));
        out.attractor.period = static_cast<int>(*p);
      }
      if (auto p = h5::ReadInt(ag.get(), "impacts_per_period")) out.attractor.impacts_per_period = *p;
      out.attractor.sticking_fraction = h5::ReadDouble(ag.get(), "sticking_fraction");
      if (auto p = h5::ReadInt(ag.get(), "searched_period")) out.attractor.searched_period = static_cast<int>(*p);
      if (auto p = h5::ReadInt(ag.get(), "recurrence_period")) out.attractor.recurrence_period = static_cast<int>(*p);
      out.attractor.recurrence_distance = h5::ReadDouble(ag.get(), "recurrence_distance");
      const auto ph = h5::ReadDoubles(ag.get(), "stick_phases");
      for (size_t i = 0; i + 1 < ph.size(); i += 2) out.attractor.stick_phases.emplace_back(ph[i], ph[i + 1]);
      out.attractor.impact_phases = h5::ReadDoubles(ag.get(), "impact_phases");
      out.attractor.impact_velocities = h5::ReadDoubles(ag.get(), "impact_velocities");
      // The contact of each sticking phase and impact (absent in files written before they were
      // stored: then unknown, empty).
      const auto contacts = [&](const char* name, size_t count) {
        std::vector<int> c;
        for (double x : h5::ReadDoubles(ag.get(), name)) {
          if (!(x >= 0 && x < 1e6 && x == std::floor(x)))
            throw std::runtime_error(fmt::format("/attractor {}: {} is not a contact index", name, x));
          c.push_back(static_cast<int>(x));
        }
        if (!c.empty() && c.size() != count)
          throw std::runtime_error(fmt::format("/attractor {}: {} values for {} events", name, c.size(), count));
        return c;
      };
      out.attractor.stick_contacts = contacts("stick_contacts", out.attractor.stick_phases.size());
      out.attractor.impact_contacts = contacts("impact_contacts", out.attractor.impact_phases.size());
    }
    out.command = h5::ReadString(f, "command");
    out.git_commit = h5::ReadString(f, "git_commit");
    out.groups = h5::ChildGroups(f);
    for (const auto& name : out.groups) out.group_notes.push_back(DescribeGroup(f, name));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {  // also a missing attribute (bad_optional_access)
    throw InputError({fmt::format("{}: not a readable vibro output file: {}", path, e.what())});
  }
  return out;
}

}  // namespace vibro
