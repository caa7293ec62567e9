// The modal data of a physical scene, enclosed (modal_enclosure.hpp).
#include "proof/modal_enclosure.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace vibro::proof {
namespace {

// "[lo, hi]": x widened by `pad` on each side, the ends written with 17 significant digits (a
// decimal within 1e-16 relative of the double, far inside the widening).
std::string Text(const Interval& x, double pad) {
  return fmt::format("[{:.17g}, {:.17g}]", x.lo() - pad, x.hi() + pad);
}

// The box of an eigenpair component: relative radius 1e-15, wide enough for the checker's
// Krawczyk test at its own precision, narrow beside the orbit's box (1e-12).
std::string BoxText(const Interval& x) {
  return Text(x, 1e-15 * (1 + std::max(std::abs(x.lo()), std::abs(x.hi()))));
}

// A modal datum, enclosed from the library's tight eigenpair enclosures (~1e-35 at 128 bits), as
// exact decimals of 34 digits rounded outward (~1e-33 relative): the orbit's proof over so thin a
// parameter set is as tight as for a point, and the checker, which encloses the true eigenpair in
// each box to 2^-120 (~1e-36), finds the datum it computes from it inside.
std::string ModelText(const Interval& x) { return x.DecimalText(34); }

// "[a, b]" (as written by Text) as the interval between the two decimals.
Interval Parse(const std::string& text) {
  const auto comma = text.find(',');
  return Union(Interval::Decimal(text.substr(1, comma - 1)), Interval::Decimal(text.substr(comma + 2, text.size() - comma - 3)));
}

std::string Decimal(double x) { return fmt::format("{}", x); }

// Re(a / b) for complex intervals, b away from 0.
Interval RealQuotient(const ComplexInterval& a, const ComplexInterval& b) {
  return (a.re * b.re + a.im * b.im) / (Sqr(b.re) + Sqr(b.im));
}

}  // namespace

ModalEnclosure EncloseModalData(const System& sys, const Scene& scene) {
  ModalEnclosure out;
  const auto& p = *scene.physical;
  const auto N = static_cast<std::size_t>(p.mass.rows());
  const auto contacts = Contacts(scene);
  // The matrices as the decimals that read back as the scene's numbers.
  std::vector<std::vector<Interval>> K(N), M(N);
  Json mass = Json::array(), stiffness = Json::array();
  for (std::size_t a = 0; a < N; ++a) {
    Json mrow = Json::array(), krow = Json::array();
    for (std::size_t b = 0; b < N; ++b) {
      const auto ia = static_cast<Eigen::Index>(a), ib = static_cast<Eigen::Index>(b);
      const std::string mt = Decimal(p.mass(ia, ib)), kt = Decimal(p.stiffness(ia, ib));
      M[a].push_back(Interval::Decimal(mt));
      K[a].push_back(Interval::Decimal(kt));
      mrow.push_back(mt);
      krow.push_back(kt);
    }
    mass.push_back(mrow);
    stiffness.push_back(krow);
  }
  // Approximate eigenpairs, ascending, to start from.
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eig(p.stiffness, p.mass);
  std::vector<double> approx(N);
  std::vector<std::vector<double>> vectors(N, std::vector<double>(N));
  for (std::size_t k = 0; k < N; ++k) {
    approx[k] = eig.eigenvalues()(static_cast<Eigen::Index>(k));
    for (std::size_t a = 0; a < N; ++a)
      vectors[a][k] = eig.eigenvectors()(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(k));
  }
  auto pairs = PencilEigenpairs(K, M, approx, vectors);
  if (pairs)  // ascending (then proven so below)
    std::sort(pairs->begin(), pairs->end(), [](const auto& x, const auto& y) { return x.value.re.mid() < y.value.re.mid(); });
  if (!pairs) {
    out.failure = "the eigenpairs of K φ = ω² M φ could not be enclosed with every eigenvalue simple (a repeated "
                  "natural frequency?): the modal data of the scene are not enclosed";
    return out;
  }
  // Contact 0's component of φ, σ_0 w_0ᵀφ.
  const auto& c0 = contacts.front();
  const Interval sigma0(c0.side == Side::kBelow ? 1.0 : -1.0);
  const auto component = [&](const std::vector<ComplexInterval>& v, const ContactSpec& c, const Interval& sigma) {
    ComplexInterval z{v[static_cast<std::size_t>(c.dof)].re, v[static_cast<std::size_t>(c.dof)].im};
    if (c.partner >= 0) {
      z.re -= v[static_cast<std::size_t>(c.partner)].re;
      z.im -= v[static_cast<std::size_t>(c.partner)].im;
    }
    return ComplexInterval{sigma * z.re, sigma * z.im};
  };
  std::vector<Interval> lambda;
  std::vector<std::vector<Interval>> psi;
  Json modes = Json::array();
  for (std::size_t k = 0; k < N; ++k) {
    const auto& pair = (*pairs)[k];
    const ComplexInterval b = component(pair.vector, c0, sigma0);
    if (!(Sqr(b.re) + Sqr(b.im)).Positive()) {
      out.failure = fmt::format("mode {} has (or may have) a node at contact 0: its modal data are not enclosed", k);
      return out;
    }
    // The tight enclosures (the modal data come from these) and the certificate's boxes around them.
    Json vec = Json::array();
    std::vector<Interval> v;
    for (std::size_t a = 0; a < N; ++a) {
      v.push_back(RealQuotient(pair.vector[a], b));
      vec.push_back(BoxText(v.back()));
    }
    lambda.push_back(pair.value.re);
    psi.push_back(v);
    modes.push_back({{"eigenvalue", BoxText(pair.value.re)}, {"vector", vec}});
  }
  for (std::size_t k = 0; k < N; ++k) {
    if (!lambda[k].Positive() || (k + 1 < N && !(lambda[k].hi() < lambda[k + 1].lo()))) {
      out.failure = "the enclosed eigenvalues of K φ = ω² M φ are not positive and separated in ascending order: the "
                    "modal data of the scene are not enclosed";
      return out;
    }
  }
  // The kept modes: the lowest sys.dof() (docs/model.md §1.3).
  const auto n = static_cast<std::size_t>(sys.dof());
  std::vector<Interval> mass_i(n);
  std::vector<Interval> omega(n), forcing(n), contact(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& v = psi[i];
    Interval m(0.0);
    for (std::size_t a = 0; a < N; ++a)
      for (std::size_t b = 0; b < N; ++b) m += v[a] * M[a][b] * v[b];
    mass_i[i] = m;
    omega[i] = Sqrt(lambda[i]);
    forcing[i] = v[static_cast<std::size_t>(p.forcing_dof)] / m;
    contact[i] = Interval(1.0) / m;
    out.omega.push_back(ModelText(omega[i]));
    out.forcing.push_back(ModelText(forcing[i]));
    out.contact.push_back(ModelText(contact[i]));
    out.shape.push_back("1");
  }
  // The floating-point data of the orbit search lie within 1e-10 (relative) of the enclosures: the
  // orbit found is then of this model, to the search's accuracy (the proof uses the enclosures only).
  const auto inside = [](const std::string& text, double x) {
    const Interval e = Parse(text);
    return e.lo() - 1e-10 * (1 + std::abs(x)) <= x && x <= e.hi() + 1e-10 * (1 + std::abs(x));
  };
  for (std::size_t i = 0; i < n; ++i) {
    const auto e = static_cast<Eigen::Index>(i);
    if (sys.contact_shape()(e) != 1.0 || !inside(out.omega[i], sys.omega()(e)) ||
        !inside(out.forcing[i], sys.forcing()(e)) || !inside(out.contact[i], sys.contact()(e))) {
      out.failure = fmt::format("the modal data of mode {} computed in floating point are not within 1e-10 of their "
                                "enclosure", i);
      return out;
    }
  }
  Json contact_json = Json::array();
  for (std::size_t j = 0; j < contacts.size(); ++j) {
    const auto& c = contacts[j];
    contact_json.push_back({{"dof", c.dof}, {"partner", c.partner}, {"side", ToString(c.side)}});
    if (j == 0) continue;
    const Interval sigma(c.side == Side::kBelow ? 1.0 : -1.0);
    std::vector<std::string> shape, proj;
    for (std::size_t i = 0; i < n; ++i) {
      const auto& v = psi[i];
      Interval w = v[static_cast<std::size_t>(c.dof)];
      if (c.partner >= 0) w -= v[static_cast<std::size_t>(c.partner)];
      const Interval cj = sigma * w;
      shape.push_back(ModelText(cj));
      proj.push_back(ModelText(cj / mass_i[i]));
      const auto& data = sys.contacts()[j];
      const auto e = static_cast<Eigen::Index>(i);
      if (!inside(shape.back(), data.shape(e)) || !inside(proj.back(), data.contact(e))) {
        out.failure = fmt::format("the modal data of contact {}, mode {}, computed in floating point are not within "
                                  "1e-10 of their enclosure", j, i);
        return out;
      }
    }
    out.more_shape.push_back(shape);
    out.more_contact.push_back(proj);
  }
  out.structure = {{"mass", mass},
                   {"stiffness", stiffness},
                   {"forcing_dof", p.forcing_dof},
                   {"contacts", contact_json},
                   {"modes", modes},
                   {"kept", n}};
  if (scene.damping_ratios.size() > 0) {
    Json zeta = Json::array();
    for (Eigen::Index k = 0; k < scene.damping_ratios.size(); ++k) zeta.push_back(Decimal(scene.damping_ratios(k)));
    out.structure["damping"] = zeta;
  }
  return out;
}

}  // namespace vibro::proof
