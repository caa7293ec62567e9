// A periodic orbit in the store (docs/output.md, /orbit): scalars and the section point as
// attributes, the Floquet multipliers as an (m, 2) [re, im] attribute.
#include "io/hdf5_store_impl.hpp"

namespace vibro {

void Hdf5Store::WriteOrbit(const OrbitResult& orbit) {
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
}

}  // namespace vibro
