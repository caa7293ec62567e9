#include "vibro/scene_toml.hpp"

#include <fmt/format.h>

namespace vibro {
namespace {

// fmt's "{}" prints a double in its shortest round-trip form; TOML needs a '.' or an exponent.
std::string Number(double v) {
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // "n": nan / inf never valid here
  return s;
}

std::string Vector(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) s += (i ? ", " : "") + Number(v[i]);
  return s + "]";
}

std::string Matrix(const Eigen::MatrixXd& m) {
  std::string s = "[";
  for (Eigen::Index i = 0; i < m.rows(); ++i) s += (i ? ", " : "") + Vector(m.row(i).transpose());
  return s + "]";
}

std::string Quoted(const std::string& text) {
  std::string s = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') s += '\\';
    if (c == '\n') {
      s += "\\n";
      continue;
    }
    s += c;
  }
  return s + "\"";
}

}  // namespace

std::string ResolvedSceneToml(const Scene& sc) {
  std::string s;
  if (!sc.title.empty()) s += fmt::format("title = {}\n\n", Quoted(sc.title));
  s += "[structure]\n";
  if (sc.modal) {
    s += fmt::format("frequencies = {}\nforcing = {}\ncontact = {}\n", Vector(sc.modal->frequencies),
                     Vector(sc.modal->forcing), Vector(sc.modal->contact));
  } else if (sc.physical) {
    s += fmt::format("mass = {}\nstiffness = {}\nforcing_dof = {}\n", Matrix(sc.physical->mass),
                     Matrix(sc.physical->stiffness), sc.physical->forcing_dof);
    if (sc.contacts.empty()) s += fmt::format("contact_dof = {}\n", sc.physical->contact_dof);
  }
  if (sc.modes > 0) s += fmt::format("modes = {}\n", sc.modes);  // either form
  if (sc.damping_ratios.size() > 0) s += fmt::format("damping_ratios = {}\n", Vector(sc.damping_ratios));
  // A compliant stop: its stiffness, damping and rule in place of a restitution (docs/compliant.md).
  const auto law = [](const Compliance& k, double r) {
    if (!k.compliant()) return fmt::format("restitution = {}\n", Number(r));
    return fmt::format("stiffness = {}\ndamping = {}\nseparation = \"{}\"\n", Number(k.stiffness),
                       Number(k.damping), ToString(k.separation));
  };
  if (sc.contacts.empty())
    s += fmt::format("\n[stop]\nposition = {}\n{}", Number(sc.stop_position), law(sc.stop_compliance, sc.restitution));
  for (const ContactSpec& k : sc.contacts) {
    s += "\n[[contact]]\n";
    if (sc.modal) {
      if (k.modal.size() > 0) s += fmt::format("modal = {}\n", Vector(k.modal));  // contact 0: none
    } else if (k.partner >= 0) {
      s += fmt::format("dofs = [{}, {}]\n", k.dof, k.partner);
    } else {
      s += fmt::format("dof = {}\n", k.dof);
    }
    s += fmt::format("side = \"{}\"\nposition = {}\n{}", ToString(k.side), Number(k.position),
                     law(k.compliance, k.restitution));
  }
  s += fmt::format("\n[excitation]\namplitude = {}\nfrequency = {}\n", Number(sc.amplitude),
                   Number(sc.frequency));
  s += fmt::format("\n[initial]\ntime = {}\n", Number(sc.initial_time));
  if (sc.initial_displacement.size() > 0)
    s += fmt::format("displacement = {}\n", Vector(sc.initial_displacement));
  else
    s += "# displacement: default (at rest on the stop with preload, at the origin with clearance)\n";
  if (sc.initial_velocity.size() > 0) s += fmt::format("velocity = {}\n", Vector(sc.initial_velocity));
  const auto& r = sc.run;
  s += fmt::format(
      "\n[run]\nperiods = {}\nengine = \"{}\"\nrtol = {}\natol = {}\nmethod = \"{}\"\nmax_step = {}\n"
      "max_steps = {}\nchatter = \"{}\"\nchatter_switch = {}\nsamples_per_period = {}\nmax_period = {}\n"
      "period_tolerance = {}\nlyapunov = {}\n",
      r.periods, ToString(r.engine), Number(r.rtol), Number(r.atol), ToString(r.method), Number(r.max_step),
      r.max_steps, ToString(r.chatter), Number(r.chatter_switch), r.samples_per_period, r.max_period,
      Number(r.period_tolerance), r.lyapunov);
  return s;
}

}  // namespace vibro
