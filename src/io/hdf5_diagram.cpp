// A diagram in the store (docs/diagram.md): the sweep as /sweep, every branch as a continuation
// branch under /diagram/branches/NNN (the layout of /branch, include/vibro/hdf5_branch.hpp), the
// coverage of the sweep's attractors as /diagram/coverage and its not-periodic ones grouped into
// windows as /diagram/uncovered_windows.
#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"

namespace vibro {

void Hdf5Store::WriteDiagram(const DiagramResult& d, const SweepSpec& spec) {
  WriteSweep(d.sweep, spec);
  impl_->Sync();
  {
    const h5::Handle g = h5::CreateGroup(impl_->file.get(), "/diagram");
    h5::WriteString(g.get(), "param", d.param);
    h5::WriteDouble(g.get(), "from", d.from);
    h5::WriteDouble(g.get(), "to", d.to);
    h5::WriteString(g.get(), "status", d.status);
    h5::WriteInt(g.get(), "branches", static_cast<long long>(d.branches.size()));
    h5::WriteInt(g.get(), "duplicates", d.duplicates);
    h5::WriteInt(g.get(), "seeds_tried", d.seeds_tried);
    h5::WriteInt(g.get(), "cap_reached", d.cap_reached ? 1 : 0);
    h5::WriteInt(g.get(), "seeds_left_out", d.seeds_left_out);
    h5::WriteInt(g.get(), "switches_left_out", d.switches_left_out);
    h5::WriteDouble(g.get(), "sweep_seconds", d.sweep_seconds);
    h5::WriteDouble(g.get(), "search_seconds", d.search_seconds);
    h5::WriteDouble(g.get(), "continuation_seconds", d.continuation_seconds);
    h5::WriteDouble(g.get(), "switching_seconds", d.switching_seconds);
    h5::WriteDouble(g.get(), "coverage_seconds", d.coverage_seconds);
    h5::WriteStrings(g.get(), "notes", d.notes);
    h5::CreateGroup(impl_->file.get(), "/diagram/branches");
  }
  for (size_t k = 0; k < d.branches.size(); ++k) {
    const auto& b = d.branches[k];
    const std::string group = fmt::format("/diagram/branches/{:03d}", k);
    {
      const h5::Handle g = h5::CreateGroup(impl_->file.get(), group);
      h5::WriteString(g.get(), "origin", b.origin);
      h5::WriteInt(g.get(), "parent", b.parent);
      h5::WriteDouble(g.get(), "born_at", b.born_at);
      h5::WriteString(g.get(), "end_first", b.end_first);
      h5::WriteString(g.get(), "end_last", b.end_last);
    }
    WriteBranch(b.branch, group);
  }
  H5Table c;
  std::vector<double> value, up, period, branch, distance;
  std::vector<std::string> kind, reason;
  for (const auto& e : d.coverage) {
    value.push_back(e.value);
    up.push_back(e.upward ? 1 : 0);
    period.push_back(e.period);
    branch.push_back(e.branch);
    distance.push_back(e.distance);
    kind.push_back(e.kind);
    reason.push_back(e.reason);
  }
  const size_t n = value.size();
  c.arrays = {{"value", {n}, value}, {"upward", {n}, up, 'u'}, {"period", {n}, period, 'i'},
              {"branch", {n}, branch, 'i'}, {"distance", {n}, distance}};
  c.strings = {{"kind", kind}, {"reason", reason}};
  WriteTable("/diagram/coverage", c);
  // The not-periodic uncovered attractors grouped into windows, as JSON's `uncovered_windows`.
  H5Table w;
  std::vector<double> w_from, w_to, w_count;
  std::vector<std::string> w_source, w_reason;
  for (const auto& x : d.uncovered_windows) {
    w_from.push_back(x.from);
    w_to.push_back(x.to);
    w_count.push_back(x.count);
    w_source.push_back(x.source);
    w_reason.push_back(x.reason);
  }
  const size_t m = w_from.size();
  w.arrays = {{"from", {m}, w_from}, {"to", {m}, w_to}, {"count", {m}, w_count, 'i'}};
  w.strings = {{"source", w_source}, {"reason", w_reason}};
  WriteTable("/diagram/uncovered_windows", w);
}

}  // namespace vibro
