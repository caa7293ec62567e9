// `vibro model SCENE`: the structural model derived from a scene (docs/cli.md).
#include <fmt/format.h>

#include "cli/cli_common.hpp"
#include "cli/text_format.hpp"
#include "vibro/scene_file.hpp"
#include "vibro/summary_json.hpp"
#include "vibro/system.hpp"

namespace {

std::string Vec(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += fmt::format("{}{:.10g}", i ? ", " : "", v[i]);
  return s + "]";
}

}  // namespace

int RunModel(const std::string& path, const std::vector<std::string>& sets, bool json) {
  const auto loaded = vibro::LoadScene(path, sets);
  const vibro::System sys(loaded.scene);
  if (json) {
    fmt::print("{}\n", vibro::ModelJson(sys));
    return 0;
  }
  fmt::print("scene               {}{}\n", path,
             loaded.scene.title.empty() ? "" : "  (" + loaded.scene.title + ")");
  fmt::print("form                {}, {} mode(s) kept\n", sys.physical() ? "physical" : "modal",
             sys.dof());
  fmt::print("frequencies ω_i     {}\n", Vec(sys.omega()));
  fmt::print("forcing T_A         {}\n", Vec(sys.forcing()));
  fmt::print("contact T_B         {}\n", Vec(sys.contact()));
  if (sys.damped()) fmt::print("damping ratios ζ_i  {}\n", Vec(sys.damping()));
  // s_A = Σ_i c_i T_A,i: zero when no mode couples A and B (e.g. a lumped chain forced and stopped
  // at different masses), up to the rounding of the sum's terms.
  const double s_A_terms = sys.contact_shape().cwiseProduct(sys.forcing()).cwiseAbs().sum();
  fmt::print("s_A, s_B            {:.10g}, {:.10g}\n", vibro::cli::SnapZero(sys.s_A(), s_A_terms) + 0.0, sys.s_B());
  fmt::print("constrained ω'_k    {}\n", Vec(sys.constrained().frequencies));
  fmt::print("static flexibility  {:.10g}\n", sys.flexibility());
  if (auto r = sys.static_reaction())
    fmt::print("static reaction     {:.10g}\n", *r);
  else
    fmt::print("static reaction     none (clearance)\n");
  fmt::print("stop x0, r          {:.10g}, {:.10g}\n", sys.stop(), sys.restitution());
  fmt::print("excitation f, ω, T  {:.10g}, {:.10g}, {:.10g}\n", sys.amplitude(), sys.frequency(),
             sys.period());
  if (sys.harmonic_sum())  // docs/harmonics.md: ω above is the base pulsation, T the common period
    for (size_t h = 0; h < sys.harmonics().size(); ++h) {
      const auto& hh = sys.harmonics()[h];
      fmt::print("  harmonic {}        f = {:.10g}, ω = {:.10g} = {}·ω_b, ψ = {:.10g}, T_A = {}\n", h, hh.amplitude,
                 hh.frequency, hh.multiple, hh.phase, Vec(hh.forcing));
    }
  // Scenes with [[contact]] tables: every contact, as written and in the modal coordinates
  // (docs/contacts.md; contact 0's are the lines above).
  if (!loaded.scene.contacts.empty() || sys.contact_count() > 1) {
    for (int j = 0; j < sys.contact_count(); ++j) {
      const vibro::ContactModel& k = sys.contacts()[static_cast<size_t>(j)];
      const std::string gap = loaded.scene.modal ? fmt::format("a{}·X", j)
                              : k.spec.partner >= 0 ? fmt::format("q{} - q{}", k.spec.dof, k.spec.partner)
                                                    : fmt::format("q{}", k.spec.dof);
      fmt::print("{:<20}{} {} {:.10g}, r {:.10g}\n", fmt::format("contact {}", j), gap,
                 k.spec.side == vibro::Side::kBelow ? ">=" : "<=", k.spec.position, k.restitution);
      fmt::print("  shape c_j         {}\n", Vec(k.shape));
      fmt::print("  contact T_j       {}\n", Vec(k.contact));
      fmt::print("  stop e_j          {:.10g}\n", k.stop);
      fmt::print("  s_A, W_jj         {:.10g}, {:.10g}\n", k.s_A, k.s_B);
      fmt::print("  constrained ω'_k  {}\n", Vec(k.constrained.frequencies));
      fmt::print("  flexibility       {:.10g}\n", k.flexibility);
    }
  }
  if (sys.physical()) {
    for (int i = 0; i < sys.dof(); ++i)
      fmt::print("mode shape ψ_{}{}     {}\n", i + 1,
                 sys.contact_shape()[i] > 0 ? "" : " (node at B)",
                 Vec(sys.mode_shapes().col(i)));
  }
  return 0;
}
