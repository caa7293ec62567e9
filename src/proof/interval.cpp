// Interval on Arb balls (the one file that includes the interval library; interval.hpp).
// Working precision 128 bits: the prover's boxes are 1e-12 wide, far above the balls' radii.
#include "proof/interval.hpp"

#include <cmath>
#include <stdexcept>

#include <acb.h>
#include <acb_mat.h>
#include <arb.h>
#include <arb_mat.h>
#include <fmt/format.h>

namespace vibro::proof {
namespace {

constexpr slong kPrec = 128;
static_assert(sizeof(arb_struct) <= 48, "Interval::storage_ is too small for an arb_struct");
static_assert(alignof(arb_struct) <= 16, "Interval::storage_ is under-aligned for an arb_struct");

}  // namespace

void* Interval::raw() { return storage_; }
const void* Interval::raw() const { return storage_; }
#define A(x) (static_cast<arb_ptr>((x).raw()))
#define CA(x) (static_cast<arb_srcptr>((x).raw()))

Interval::Interval() { arb_init(A(*this)); }
Interval::Interval(double value) {
  arb_init(A(*this));
  arb_set_d(A(*this), value);
}
Interval::Interval(const Interval& other) {
  arb_init(A(*this));
  arb_set(A(*this), CA(other));
}
Interval::Interval(Interval&& other) noexcept {
  arb_init(A(*this));
  arb_swap(A(*this), A(other));
}
Interval& Interval::operator=(const Interval& other) {
  if (this != &other) arb_set(A(*this), CA(other));
  return *this;
}
Interval& Interval::operator=(Interval&& other) noexcept {
  arb_swap(A(*this), A(other));
  return *this;
}
Interval::~Interval() { arb_clear(A(*this)); }

Interval Interval::Decimal(const std::string& text) {
  Interval x;
  // arb_set_str accepts "[m +/- r]" too: a parameter is a plain decimal only.
  if (text.empty() || text.find_first_not_of("0123456789.eE+-") != std::string::npos ||
      arb_set_str(A(x), text.c_str(), kPrec) != 0)
    throw std::invalid_argument("not a decimal number: '" + text + "'");
  return x;
}

Interval Interval::Hull(double lo, double hi) {
  if (!(lo <= hi)) throw std::invalid_argument(fmt::format("empty interval [{}, {}]", lo, hi));
  Interval x;
  arf_t a, b;
  arf_init(a);
  arf_init(b);
  arf_set_d(a, lo);
  arf_set_d(b, hi);
  arb_set_interval_arf(A(x), a, b, kPrec);
  arf_clear(a);
  arf_clear(b);
  return x;
}

Interval Interval::Pi() {
  Interval x;
  arb_const_pi(A(x), kPrec);
  return x;
}

double Interval::lo() const {
  arf_t t;
  arf_init(t);
  arb_get_lbound_arf(t, CA(*this), kPrec);
  const double d = arf_get_d(t, ARF_RND_FLOOR);
  arf_clear(t);
  return d;
}
double Interval::hi() const {
  arf_t t;
  arf_init(t);
  arb_get_ubound_arf(t, CA(*this), kPrec);
  const double d = arf_get_d(t, ARF_RND_CEIL);
  arf_clear(t);
  return d;
}
double Interval::mid() const { return arf_get_d(arb_midref(CA(*this)), ARF_RND_NEAR); }
bool Interval::finite() const { return arb_is_finite(CA(*this)) != 0; }
bool Interval::Positive() const { return arb_is_positive(CA(*this)) != 0; }
bool Interval::Negative() const { return arb_is_negative(CA(*this)) != 0; }
bool Interval::Contains(double x) const {
  arf_t t;
  arf_init(t);
  arf_set_d(t, x);
  const bool in = arb_contains_arf(CA(*this), t) != 0;
  arf_clear(t);
  return in;
}
bool Interval::Contains(const Interval& other) const { return arb_contains(CA(*this), CA(other)) != 0; }
bool Interval::InsideOpen(double lo, double hi) const {
  return finite() && this->lo() > lo && this->hi() < hi;
}

Interval& Interval::operator+=(const Interval& b) {
  arb_add(A(*this), CA(*this), CA(b), kPrec);
  return *this;
}
Interval& Interval::operator-=(const Interval& b) {
  arb_sub(A(*this), CA(*this), CA(b), kPrec);
  return *this;
}
Interval& Interval::operator*=(const Interval& b) {
  arb_mul(A(*this), CA(*this), CA(b), kPrec);
  return *this;
}
Interval& Interval::operator/=(const Interval& b) {
  arb_div(A(*this), CA(*this), CA(b), kPrec);
  return *this;
}
Interval Interval::operator-() const {
  Interval x;
  arb_neg(A(x), CA(*this));
  return x;
}

Interval Sin(const Interval& x) {
  Interval y;
  arb_sin(A(y), CA(x), kPrec);
  return y;
}
Interval Cos(const Interval& x) {
  Interval y;
  arb_cos(A(y), CA(x), kPrec);
  return y;
}
Interval Sqrt(const Interval& x) {
  Interval y;
  arb_sqrtpos(A(y), CA(x), kPrec);
  return y;
}
Interval Asin(const Interval& x) {
  Interval y;
  arb_asin(A(y), CA(x), kPrec);
  return y;
}
Interval Exp(const Interval& x) {
  Interval y;
  arb_exp(A(y), CA(x), kPrec);
  return y;
}
Interval Abs(const Interval& x) {
  Interval y;
  arb_abs(A(y), CA(x));
  return y;
}
Interval Sqr(const Interval& x) {
  Interval y;
  arb_sqr(A(y), CA(x), kPrec);
  return y;
}
Interval Union(const Interval& a, const Interval& b) {
  Interval y;
  arb_union(A(y), CA(a), CA(b), kPrec);
  return y;
}

namespace {
// An end of `x` as an exact decimal of about `digits` significant digits: floor(lo·10^k) − 1 (or
// ceil(hi·10^k) + 1) times 10^−k, every rounding directed outward.
std::string DecimalEnd(const arb_struct* x, int digits, bool upper) {
  arf_t end, scale, y;
  arf_init(end);
  arf_init(scale);
  arf_init(y);
  if (upper) arb_get_ubound_arf(end, x, kPrec);
  else arb_get_lbound_arf(end, x, kPrec);
  const double mag = std::abs(arf_get_d(end, ARF_RND_NEAR));
  const long k = mag > 0 ? digits - 1 - static_cast<long>(std::floor(std::log10(mag))) : digits;
  fmpz_t p;
  fmpz_init(p);
  fmpz_ui_pow_ui(p, 10, static_cast<ulong>(k >= 0 ? k : -k));
  arf_set_fmpz(scale, p);
  const arf_rnd_t rnd = upper ? ARF_RND_CEIL : ARF_RND_FLOOR;
  if (k >= 0) arf_mul(y, end, scale, 4 * kPrec, rnd);
  else arf_div(y, end, scale, 4 * kPrec, rnd);
  arf_get_fmpz(p, y, rnd);
  if (upper) fmpz_add_ui(p, p, 1);
  else fmpz_sub_ui(p, p, 1);
  char* digits_text = fmpz_get_str(nullptr, 10, p);
  std::string out = fmt::format("{}e{}", digits_text, -k);
  flint_free(digits_text);
  fmpz_clear(p);
  arf_clear(end);
  arf_clear(scale);
  arf_clear(y);
  return out;
}
}  // namespace

std::string Interval::DecimalText(int digits) const {
  return fmt::format("[{}, {}]", DecimalEnd(CA(*this), digits, false), DecimalEnd(CA(*this), digits, true));
}

std::string Interval::ToString() const { return fmt::format("[{:.17g}, {:.17g}]", lo(), hi()); }

std::optional<std::vector<ComplexInterval>> Eigenvalues(const std::vector<std::vector<Interval>>& a,
                                                        const std::vector<std::complex<double>>& approx,
                                                        const std::vector<std::vector<std::complex<double>>>& vectors) {
  const slong n = static_cast<slong>(a.size());
  acb_mat_t m, r_approx;
  acb_mat_init(m, n, n);
  acb_mat_init(r_approx, n, n);
  acb_ptr e = _acb_vec_init(n), e_approx = _acb_vec_init(n);
  for (slong i = 0; i < n; ++i) {
    acb_set_d_d(e_approx + i, approx[static_cast<size_t>(i)].real(), approx[static_cast<size_t>(i)].imag());
    for (slong j = 0; j < n; ++j) {
      const auto ui = static_cast<size_t>(i), uj = static_cast<size_t>(j);
      acb_set_arb(acb_mat_entry(m, i, j), CA(a[ui][uj]));
      acb_set_d_d(acb_mat_entry(r_approx, i, j), vectors[ui][uj].real(), vectors[ui][uj].imag());
    }
  }
  // Rump's method: every eigenvalue of every matrix in the ball matrix m, certified simple.
  const int ok = acb_mat_eig_simple_rump(e, nullptr, nullptr, m, e_approx, r_approx, kPrec);
  std::optional<std::vector<ComplexInterval>> out;
  if (ok) {
    out.emplace();
    for (slong i = 0; i < n; ++i) {
      ComplexInterval z;
      arb_set(A(z.re), acb_realref(e + i));
      arb_set(A(z.im), acb_imagref(e + i));
      out->push_back(std::move(z));
    }
  }
  _acb_vec_clear(e, n);
  _acb_vec_clear(e_approx, n);
  acb_mat_clear(m);
  acb_mat_clear(r_approx);
  return out;
}

std::optional<std::vector<EigenpairEnclosure>> PencilEigenpairs(const std::vector<std::vector<Interval>>& K,
                                                                const std::vector<std::vector<Interval>>& M,
                                                                const std::vector<double>& approx,
                                                                const std::vector<std::vector<double>>& vectors) {
  const slong n = static_cast<slong>(K.size());
  arb_mat_t k, m, a;
  arb_mat_init(k, n, n);
  arb_mat_init(m, n, n);
  arb_mat_init(a, n, n);
  acb_mat_t ac, r, r_approx;
  acb_mat_init(ac, n, n);
  acb_mat_init(r, n, n);
  acb_mat_init(r_approx, n, n);
  acb_ptr e = _acb_vec_init(n), e_approx = _acb_vec_init(n);
  for (slong i = 0; i < n; ++i) {
    const auto ui = static_cast<size_t>(i);
    acb_set_d(e_approx + i, approx[ui]);
    for (slong j = 0; j < n; ++j) {
      const auto uj = static_cast<size_t>(j);
      arb_set(arb_mat_entry(k, i, j), CA(K[ui][uj]));
      arb_set(arb_mat_entry(m, i, j), CA(M[ui][uj]));
      acb_set_d(acb_mat_entry(r_approx, i, j), vectors[ui][uj]);
    }
  }
  // A = M⁻¹K encloses M⁻¹K for every M, K in the balls: its eigenpairs are the pencil's. Rump's
  // method encloses every eigenvalue, certified simple, and a right eigenvector of each.
  std::optional<std::vector<EigenpairEnclosure>> out;
  if (arb_mat_solve(a, m, k, kPrec) != 0) {
    acb_mat_set_arb_mat(ac, a);
    // Approximations at the working precision (QR from the doubles' ones; kept if QR fails), so
    // that the enclosures are as tight as the balls allow (~1e-35), not as the doubles (~1e-16).
    acb_mat_t mid_a;
    acb_mat_init(mid_a, n, n);
    acb_mat_get_mid(mid_a, ac);
    acb_ptr e_fine = _acb_vec_init(n);
    acb_mat_t r_fine;
    acb_mat_init(r_fine, n, n);
    _acb_vec_set(e_fine, e_approx, n);
    acb_mat_set(r_fine, r_approx);
    if (acb_mat_approx_eig_qr(e_fine, nullptr, r_fine, mid_a, nullptr, 0, kPrec) != 0) {
      _acb_vec_set(e_approx, e_fine, n);
      acb_mat_set(r_approx, r_fine);
    }
    _acb_vec_clear(e_fine, n);
    acb_mat_clear(r_fine);
    acb_mat_clear(mid_a);
    if (acb_mat_eig_simple_rump(e, nullptr, r, ac, e_approx, r_approx, kPrec) != 0) {
      out.emplace();
      for (slong i = 0; i < n; ++i) {
        EigenpairEnclosure pair;
        arb_set(A(pair.value.re), acb_realref(e + i));
        arb_set(A(pair.value.im), acb_imagref(e + i));
        for (slong j = 0; j < n; ++j) {
          ComplexInterval z;
          arb_set(A(z.re), acb_realref(acb_mat_entry(r, j, i)));
          arb_set(A(z.im), acb_imagref(acb_mat_entry(r, j, i)));
          pair.vector.push_back(std::move(z));
        }
        out->push_back(std::move(pair));
      }
    }
  }
  _acb_vec_clear(e, n);
  _acb_vec_clear(e_approx, n);
  acb_mat_clear(ac);
  acb_mat_clear(r);
  acb_mat_clear(r_approx);
  arb_mat_clear(k);
  arb_mat_clear(m);
  arb_mat_clear(a);
  return out;
}

std::string LibraryVersions() { return fmt::format("arb {}, flint {}", arb_version, FLINT_VERSION); }

}  // namespace vibro::proof
