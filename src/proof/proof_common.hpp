// What the proofs of src/proof share: the outcome of a proof, the record of the inequalities it
// verified (the certificate's "inequalities", docs/prove.md), and intervals as JSON pairs.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include "proof/enclosure.hpp"
#include "proof/interval.hpp"
#include "proof/positivity.hpp"
#include "vibro/prove.hpp"

namespace vibro::proof {

using Json = nlohmann::json;

inline Json Pair(const Interval& x) { return Json::array({x.lo(), x.hi()}); }

// Every inequality a proof rests on, with its enclosure: the checker recomputes each.
class Ledger {
 public:
  // relation: "> 0", "< 0", "inside" (with the bounds in `detail`), ...
  bool Check(bool holds, const std::string& name, const std::string& where, const Interval& enclosure,
             const std::string& relation) {
    list_.push_back({{"name", name}, {"where", where}, {"enclosure", Pair(enclosure)}, {"relation", relation},
                     {"holds", holds}});
    if (!holds && failed_.empty())
      failed_ = name + " " + relation + " fails at " + where + ": enclosure " + enclosure.ToString();
    return holds;
  }
  const Json& list() const { return list_; }
  const std::string& failed() const { return failed_; }

 private:
  Json list_ = Json::array();
  std::string failed_;
};

struct Outcome {
  bool proven = false;
  std::string reason;
  Json summary = Json::object();      // the --json fields of the orbit (events, section, ...)
  Json certificate = Json::object();  // the kind-specific part of the certificate
};

// An impacting orbit as the Poincaré solver found it: the q-period orbit's impacts, each with
// its absolute time and the modal state just after it.
struct ImpactGuess {
  int period = 0;
  std::vector<double> times;
  std::vector<Eigen::VectorXd> X, V;
  // The contact of each impact (a model of several contacts); empty: all at contact 0.
  std::vector<int> contacts;
  // Over a parameter interval: |u(end) − u(start)| per unknown (t_j, X_j, V_j), which the box must
  // cover beyond the default radius; empty for one parameter value.
  std::vector<double> spread;
};

// Over a parameter interval P on which the residual depends affinely (the amplitude, contact 0's
// stop position or its restitution; docs/prove.md "Along a branch"): the model at each end of P.
// Krawczyk's constant term ũ − C F(ũ, p) is then affine in p, and its range over P is the hull of its
// values at the two ends (the centred form, exact for an affine parameter).
struct AffineEnds {
  IntervalModel lo, hi;
};

// frequency_interval: the model's forcing frequency is the parameter interval P of a segment; the
// residual is not affine in it, and Krawczyk's constant term takes the mean-value form in ω
// (impact_proof.cpp CentreInFrequency; docs/prove.md "Along a branch").
Outcome ProveImpactOrbit(const IntervalModel& model, const ImpactGuess& guess, const ProofRequest& request,
                         const Budget& budget, const AffineEnds* ends = nullptr, bool frequency_interval = false);
// A sticking orbit of several modes held on contact 0 with plastic landings (r = 0), as the
// Poincaré solver found it: the release (time, modal state), then each landing (time, state just
// after the plastic impact); every landing but the last departs at once (R < 0), the last sticks
// until the release q periods after the first.
struct StickingGuess {
  int period = 0;
  double release_time = 0;
  Eigen::VectorXd X_release, V_release;
  std::vector<double> landing_times;
  std::vector<Eigen::VectorXd> X, V;
};
Outcome ProveStickingModes(const IntervalModel& model, const StickingGuess& guess, const ProofRequest& request,
                           const Budget& budget);

// One-DOF, r = 0: the release phase is fixed by the model (docs/model.md §4.4), so no guess.
Outcome ProveSticking1Dof(const IntervalModel& model, const ProofRequest& request, const Budget& budget);

// A proof of an orbit of least period p (outcome.summary["period"]) asked for at a period Q that p
// divides: the summary gains "requested_period": Q and the reason says that the orbit is also the
// period-Q orbit (docs/prove.md "The period is the least period").
inline void StateLeastPeriod(Outcome& outcome, int requested) {
  const int p = outcome.summary["period"].get<int>();
  outcome.summary["requested_period"] = requested;
  outcome.reason += "; its least period " + std::to_string(p) + " divides the requested period " +
                    std::to_string(requested) + ", so it is also the period-" + std::to_string(requested) + " orbit";
}

// The monodromy of an impacting orbit enclosed over the box U of its unknowns (t_j, X_j, V_j per
// impact, as ProveImpactOrbit's) and the model's parameter intervals (impact_proof.cpp).
std::vector<std::vector<Interval>> ImpactMonodromy(const IntervalModel& model, const std::vector<int>& contacts,
                                                   int impacts, int q, const std::vector<Interval>& U);

// Krawczyk's test in the tube along the family's tangent (impact_proof.cpp TangentTest) over the
// model's frequency interval, from the orbit `guess` near its middle: for every ω of the interval
// exactly one orbit in u + tangent(ω − centre) + W; K holds it (the certificate's "krawczyk" form).
struct SubTube {
  bool proven = false;
  double centre = 0;
  std::vector<double> u, tangent;
  std::vector<Interval> W, K;
};
SubTube TangentOrbits(const IntervalModel& model, const std::vector<int>& contacts, int impacts, int q,
                      const std::vector<double>& guess, double radius);

// Over a segment in the forcing frequency (a certificate with a `tangent`, impact_proof.cpp
// TangentTest): the spectral radius of the monodromy below 1 for every frequency of the segment,
// proven on sub-pieces P_k (halved where the bound fails) from the monodromy over the sub-tubes
// ũ + a(P_k − ω̃) + W (segment_stability.cpp, docs/prove.md "Stability along a segment").
// model_at(text): the model with the frequency at the decimal interval text "[a, b]".
struct SegmentStability {
  bool proven = false;
  Json certificate;    // the certificate's "spectral_bound"
  double bound = 0;    // the largest claimed bound
  int pieces = 0;
  std::string reason;  // why not proven
};
SegmentStability ProveSegmentStability(const std::function<IntervalModel(const std::string&)>& model_at,
                                       const std::string& lo, const std::string& hi, const Json& certificate,
                                       int q, const Budget& budget);
inline constexpr const char* kSegmentStableNote =
    "the spectral radius of the monodromy is below 1 for every frequency of the interval (spectral_bound: a "
    "similarity by the eigenvectors of a midpoint monodromy and a block norm, on sub-pieces)";

// ωt mod 2π, enclosed (the integer number of turns taken from the midpoint).
Interval Phase(const IntervalModel& model, const Interval& t);
// Floquet multipliers of an enclosed monodromy matrix (2n × 2n) and the verdict on stability.
struct Spectrum {
  bool enclosed = false;
  Json multipliers = Json::array();  // [{"re": [lo, hi], "im": [lo, hi]}, ...]
  std::string stability = "undecided";
  std::string note;
};
Spectrum Multipliers(const std::vector<std::vector<Interval>>& monodromy);

}  // namespace vibro::proof
