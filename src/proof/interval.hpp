// Rigorous interval arithmetic for the prover (docs/prove.md): a closed real interval that is
// guaranteed to contain the exact value of every expression computed with it. The only file of
// vibro that sees the interval library (Arb, a ball arithmetic with correctly rounded elementary
// functions; FLINT underneath) is interval.cpp.
//
// Every operation encloses the exact result for all values of its arguments inside their intervals.
// Bounds read back as doubles are rounded outwards, so [lo(), hi()] contains the interval.
#pragma once

#include <complex>
#include <optional>
#include <string>
#include <vector>

namespace vibro::proof {

class Interval {
 public:
  Interval();                  // the point 0
  Interval(double value);      // NOLINT: the point `value` (exact)
  Interval(const Interval& other);
  Interval(Interval&& other) noexcept;
  Interval& operator=(const Interval& other);
  Interval& operator=(Interval&& other) noexcept;
  ~Interval();

  // The exact value of a decimal number ("1.1", "-2.5e-3"): an interval of a few ulps of the
  // working precision (128 bits) around it. Throws std::invalid_argument if `text` is not one.
  static Interval Decimal(const std::string& text);
  // [lo, hi] (lo ≤ hi, both finite).
  static Interval Hull(double lo, double hi);
  static Interval Pi();

  double lo() const;   // rounded down
  double hi() const;   // rounded up
  double mid() const;  // nearest double to the midpoint
  double width() const { return hi() - lo(); }
  bool finite() const;

  bool Positive() const;  // every point > 0
  bool Negative() const;  // every point < 0
  bool Contains(double x) const;
  bool Contains(const Interval& other) const;
  // lo < other's every point ... : this interval lies in the open interior of [lo, hi].
  bool InsideOpen(double lo, double hi) const;

  Interval& operator+=(const Interval& b);
  Interval& operator-=(const Interval& b);
  Interval& operator*=(const Interval& b);
  Interval& operator/=(const Interval& b);  // b must not contain 0 (else an unbounded result)
  friend Interval operator+(Interval a, const Interval& b) { return a += b; }
  friend Interval operator-(Interval a, const Interval& b) { return a -= b; }
  friend Interval operator*(Interval a, const Interval& b) { return a *= b; }
  friend Interval operator/(Interval a, const Interval& b) { return a /= b; }
  Interval operator-() const;

  friend Interval Sin(const Interval& x);
  friend Interval Cos(const Interval& x);
  friend Interval Sqrt(const Interval& x);   // of the non-negative part
  friend Interval Asin(const Interval& x);
  friend Interval Exp(const Interval& x);
  friend Interval Abs(const Interval& x);
  friend Interval Sqr(const Interval& x);
  friend Interval Union(const Interval& a, const Interval& b);  // convex hull

  // "[lo, hi]" with 17 significant digits, outward.
  std::string ToString() const;
  // "[lo, hi]" as exact decimals of `digits` significant digits ("7962252170181254e-16"), each end
  // rounded outward and moved one more unit of its last digit out: a text interval that contains
  // this one with a margin (for the modal data of a physical scene, docs/prove.md).
  std::string DecimalText(int digits) const;

  // The Arb ball inside (an arb_struct): for interval.cpp only.
  void* raw();
  const void* raw() const;

 private:
  alignas(16) unsigned char storage_[48];  // an arb_struct (static_assert in interval.cpp)
};

// A complex interval (rectangle) re + i·im.
struct ComplexInterval {
  Interval re, im;
};

// Enclosures of all eigenvalues of every matrix in the square interval matrix `a` (row-major),
// when they are simple and separated; nullopt when that cannot be certified. `approx` are the
// approximate eigenvalues and `vectors` the approximate right eigenvectors (columns, row-major
// n × n) to start from.
std::optional<std::vector<ComplexInterval>> Eigenvalues(const std::vector<std::vector<Interval>>& a,
                                                        const std::vector<std::complex<double>>& approx,
                                                        const std::vector<std::vector<std::complex<double>>>& vectors);

// An eigenvalue and a right eigenvector of a matrix pencil, enclosed.
struct EigenpairEnclosure {
  ComplexInterval value;
  std::vector<ComplexInterval> vector;
};

// Enclosures of all N eigenpairs of the pencil K φ = λ M φ (N × N interval matrices, row-major,
// M invertible), for every K and M in the intervals, when every eigenvalue is simple: λ_k and one
// eigenvector φ_k each (its scaling is the library's: only directions are meaningful). `approx`
// are approximate eigenvalues and `vectors` approximate eigenvectors (columns, row-major N × N).
// nullopt when that cannot be certified (M not provably invertible, an eigenvalue not provably
// simple).
std::optional<std::vector<EigenpairEnclosure>> PencilEigenpairs(const std::vector<std::vector<Interval>>& K,
                                                                const std::vector<std::vector<Interval>>& M,
                                                                const std::vector<double>& approx,
                                                                const std::vector<std::vector<double>>& vectors);

// "arb 2.x.y, flint 2.9.0": the interval library as linked.
std::string LibraryVersions();

}  // namespace vibro::proof
