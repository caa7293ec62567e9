// A periodic orbit in the store (docs/output.md, /orbit): scalars and the section point as
// attributes, the Floquet multipliers as an (m, 2) [re, im] attribute, the contact sequence of an
// orbit with several contacts as a string attribute, a compliant orbit's contact phases as a table.
#include <vector>

#include <fmt/format.h>

#include "io/hdf5_store_impl.hpp"

namespace vibro {

void Hdf5Store::WriteOrbit(const OrbitResult& orbit) {
  impl_->Sync();
  const h5::Handle g = h5::OpenOrCreateGroup(impl_->file.get(), "/orbit");
  const h5::Id o = g.get();
  h5::WriteInt(o, "period", orbit.period);
  h5::WriteInt(o, "newton_iterations", orbit.newton_iterations);
  h5::WriteBool(o, "stable", orbit.stable);
  h5::WriteDouble(o, "residual", orbit.residual);
  h5::WriteDouble(o, "section_time", orbit.section_time);
  h5::WriteDoubles(o, "X", {orbit.X.data(), orbit.X.data() + orbit.X.size()});
  h5::WriteDoubles(o, "V", {orbit.V.data(), orbit.V.data() + orbit.V.size()});
  std::vector<double> mu;
  for (const auto& z : orbit.multipliers) {
    mu.push_back(z.real());
    mu.push_back(z.imag());
  }
  // (m, 2) as [re, im]; (0, 2) for none (one-DOF sticking orbits).
  h5::WriteDoubles(o, "multipliers", mu, 2);
  // Several contacts: the contact sequence, and why there are no multipliers when the map has no
  // Jacobian on the orbit (docs/output.md).
  if (!orbit.sequence.empty()) h5::WriteString(o, "sequence", orbit.sequence);
  if (!orbit.no_jacobian.empty()) h5::WriteString(o, "no_jacobian", orbit.no_jacobian);
  // Compliant stops: each contact phase of the orbit's q periods with its exact loads, one row per
  // phase in order from the section (docs/compliant.md, "Periodic orbits"; docs/output.md).
  if (!orbit.contact_phases.empty()) {
    H5Table t;
    const size_t P = orbit.contact_phases.size();
    const auto col = [&](const char* name, double OrbitResult::ContactPhase::*field) {
      std::vector<double> v;
      for (const auto& p : orbit.contact_phases) v.push_back(p.*field);
      t.arrays.push_back({name, {P}, std::move(v)});
    };
    std::vector<double> contact;
    for (const auto& p : orbit.contact_phases) contact.push_back(p.contact);
    t.arrays.push_back({"contact", {P}, std::move(contact), 'i'});
    col("entry", &OrbitResult::ContactPhase::entry);
    col("exit", &OrbitResult::ContactPhase::exit);
    col("duration", &OrbitResult::ContactPhase::duration);
    col("entry_velocity", &OrbitResult::ContactPhase::entry_velocity);
    col("exit_velocity", &OrbitResult::ContactPhase::exit_velocity);
    col("peak_force", &OrbitResult::ContactPhase::peak_force);
    col("peak_time", &OrbitResult::ContactPhase::peak_time);
    col("penetration", &OrbitResult::ContactPhase::penetration);
    col("impulse", &OrbitResult::ContactPhase::impulse);
    col("energy_dissipated", &OrbitResult::ContactPhase::dissipated);
    WriteTable("/orbit/contact_phases", t);
  }
}

InitialOverride ReadOrbitSection(const std::string& path) {
  h5::Silence();
  const h5::Handle file = h5::OpenFile(path, false);
  if (!file) throw store::CannotOpen(path);
  if (!h5::Exists(file.get(), "/orbit")) throw InputError({fmt::format("{}: no group /orbit in this file (not a file of `vibro orbit --out`)", path)});
  const h5::Handle g = h5::OpenGroup(file.get(), "/orbit");
  const auto t = h5::ReadDouble(g.get(), "section_time");
  const auto X = h5::ReadDoubles(g.get(), "X"), V = h5::ReadDoubles(g.get(), "V");
  if (!t || X.empty() || X.size() != V.size())
    throw InputError({fmt::format("{}: /orbit: expected section_time, X and V (a file of `vibro orbit --out`)", path)});
  return {*t, Eigen::Map<const Eigen::VectorXd>(X.data(), static_cast<Eigen::Index>(X.size())),
          Eigen::Map<const Eigen::VectorXd>(V.data(), static_cast<Eigen::Index>(V.size()))};
}

}  // namespace vibro
