// The automaton's transitions at a compliant stop (docs/compliant.md): entry into a contact phase,
// its segments and loads, its exit by the stop's separation rule, and the relaxing flight that a
// force-rule exit leaves. Included at the end of automaton.hpp; the law itself (the closed forms,
// the certified roots) is dynamics/compliant_contact.hpp.
#pragma once

#include <cmath>
#include <limits>
#include <type_traits>

#include "dynamics/automaton.hpp"

namespace vibro::detail {

template <class S>
void Automaton<S>::BuildCompliant() {
  compliant_.resize(models_.size());
  compliant_account_.assign(models_.size(), {});
  if constexpr (std::is_same_v<S, double>) {
    for (size_t j = 0; j < models_.size(); ++j) {
      if (!models_[j]->compliant) continue;
      if (cvode_) compliant_[j] = MakeCvodeCompliant(run_, models_, static_cast<int>(j));
      else compliant_[j] = std::make_unique<CompliantPropagator>(models_, static_cast<int>(j));
      compliant_[j]->SetStopPoll([this] { return StopPolled(); });
      if (!compliant_[j]->error().empty() && violation_.empty())
        violation_ = fmt::format("compliant contact {}: {}", j, compliant_[j]->error());
    }
  }
}

// The propagator of the current mode when a compliant stop owns it: its contact phase, or the
// relaxing flight after a force-rule exit. Null otherwise.
template <class S>
PropagatorT<S>* Automaton<S>::CompliantPropagatorNow() {
  if (InCompliantPhase()) return compliant_[static_cast<size_t>(active_)].get();
  if (mode_ == Mode::kFree && relaxing_) return compliant_[static_cast<size_t>(relax_contact_)].get();
  return nullptr;
}

// The gap of compliant contact k reached 0 in free flight (or, in a relaxing flight, the gap to its
// surface): a contact phase begins, without any reset (the state is continuous). A touch that the
// flow does not push into the stop (ġ = 0 and R ≤ 0, the rigid stop's test of docs/model.md §2.1)
// is a grazing, as at a rigid stop.
template <class S>
bool Automaton<S>::EnterContactPhase(int k) {
  if constexpr (!std::is_same_v<S, double>) {
    return Fail("a compliant stop needs the exact engine in double precision");
  } else {
    const ModelT<S>& m = M(k);
    const bool recontact = relaxing_ && relax_contact_ == k;
    if (relaxing_ && !recontact)
      return Fail(fmt::format("contact {} closes while the surface of compliant contact {} still relaxes (t = "
                              "{:.17g}): not supported; a stiffer stop, or less damping, relaxes sooner",
                              k, relax_contact_, AbsTime(clock_)));
    // The surface's velocity: ẏ = −(k/c) y while it relaxes, 0 at rest.
    const S surface_rate = recontact ? S(-m.stiffness / m.damping * relax_y_) : S(0);
    if (!recontact) X_ -= m.contact * ((m.ContactDisplacement(X_) - m.x0) / m.s_B);  // g = 0 to rounding
    const S v = m.ContactVelocity(V_);
    const S floor = S(1000) * Eps<S>() * m.shape.cwiseProduct(V_).cwiseAbs().sum();
    active_ = k;
    if (!recontact && !(v < -floor)) {
      const S* sc = SinCos(Phase(clock_));
      if (!(m.ReactionSin(X_, V_, sc[0]) > 0)) {  // not pushed in: a touch, the flight goes on
        NotifyReset(ResetKind::kGrazing, X_, V_, k);  // the maps are not smooth there
        Emit(EventKind::kGrazing, v, v, k);
        m.ProjectOntoStop(X_, V_);
        Depart(FlightStart::kDeparture);
        gap_ = 0;
        if (multi()) gaps_[static_cast<size_t>(k)] = 0;
        return true;
      }
    }
    relaxing_ = false;
    relax_contact_ = -1;
    relax_y_ = 0;
    compliant_[static_cast<size_t>(k)]->SetSurface(0);
    mode_ = Mode::kSticking;
    stick_start_ = StickStart::kGeneric;
    chatter_first_ = chatter_last_ = 0;
    gap_ = 0;
    compliant_account_[static_cast<size_t>(k)] = {};
    NotifyCompliant(ResetKind::kCompliantEntry, k, S(v - surface_rate), recontact ? relax_y_ : S(0), recontact);
    Emit(EventKind::kStick, S(v - surface_rate), S(v - surface_rate), k);
    return true;
  }
}

// After a segment run by a compliant propagator (the clock already advanced): the phase's loads,
// then its end: the exit of a contact phase, a re-contact or the end of a relaxing flight, or
// another contact's gap closing.
template <class S>
bool Automaton<S>::AfterCompliantSegment(const SegmentResultT<S>& seg, const ClockT<S>& from) {
  if constexpr (!std::is_same_v<S, double>) {
    (void)seg;
    (void)from;
    return Fail("a compliant stop needs the exact engine in double precision");
  } else {
    const int k = mode_ == Mode::kSticking ? active_ : relax_contact_;
    CompliantPhase& p = *compliant_[static_cast<size_t>(k)];
    const ModelT<S>& m = M(k);
    if (mode_ == Mode::kSticking) {
      if (opt_.loads && !opt_.observers.empty()) {
        const auto L = p.Loads(seg.sigma);
        loads_.AddCompliant(k, seg.sigma, L.integral, L.peak);
        CompliantAccount& a = compliant_account_[static_cast<size_t>(k)];
        if (L.peak > a.peak) {
          a.peak = L.peak;
          a.peak_time = AbsTime(from) + L.peak_at;
        }
        a.penetration = std::max(a.penetration, L.penetration);
        a.dissipated += L.dissipated;
      }
      if (multi())
        for (size_t j = 0; j < models_.size(); ++j)
          gaps_[j] = models_[j]->ContactDisplacement(X_) - models_[j]->x0;
      if (seg.end == SegmentEnd::kLimit) return true;
      if (seg.end == SegmentEnd::kContact)
        return Fail(fmt::format("contact {} ({}) closes during the contact phase of compliant contact {} at t = "
                                "{:.17g}: two contacts at once with a compliant stop are not supported",
                                seg.contact, multi() ? labels_[static_cast<size_t>(seg.contact)] : "",
                                k, AbsTime(clock_)));
      if (seg.end != SegmentEnd::kRelease) return Fail("compliant contact phase: " + seg.message);
      // The exit: the gap (rule "gap", or no dashpot) or the force (rule "force") back at 0.
      const S g = m.ContactDisplacement(X_) - m.x0;
      const S v = m.ContactVelocity(V_);
      const bool by_gap = m.separation == Separation::kGap || m.damping == 0;
      if (!by_gap && g < 0) {
        // The spring's energy left in the surface is lost as it relaxes through the dashpot.
        compliant_account_[static_cast<size_t>(k)].dissipated += 0.5 * m.stiffness * g * g;
      }
      const bool relaxes = !by_gap && g < 0;
      NotifyCompliant(ResetKind::kCompliantExit, k, v, relaxes ? g : S(0), relaxes);
      Emit(EventKind::kRelease, v, v, k);
      mode_ = Mode::kFree;
      if (by_gap || !(g < 0)) {
        X_ -= m.contact * (g / m.s_B);  // on the stop to rounding
        gap_ = 0;
        Depart(v > 0 ? FlightStart::kAfterImpact : FlightStart::kDeparture);
        if (multi()) gaps_[static_cast<size_t>(k)] = 0;
        return true;
      }
      // A force-rule exit inside the stop: the relaxing flight, its gap measured to the surface.
      relaxing_ = true;
      relax_contact_ = k;
      relax_y_ = g;
      p.SetSurface(g, true);
      gap_ = 0;
      Depart(FlightStart::kDeparture);
      if (multi()) gaps_[static_cast<size_t>(k)] = 0;
      return true;
    }
    // A relaxing flight.
    const S y = p.SurfaceAt(seg.sigma);
    if (multi())
      for (size_t j = 0; j < models_.size(); ++j)
        gaps_[j] = models_[j]->ContactDisplacement(X_) - models_[j]->x0 - (static_cast<int>(j) == k ? y : S(0));
    if (seg.end == SegmentEnd::kContact && seg.contact == k) {
      relax_y_ = y;
      return EnterContactPhase(k);
    }
    if (seg.end == SegmentEnd::kContact) {
      relax_y_ = y;
      return EnterContactPhase(seg.contact);  // refused while the surface relaxes (its message)
    }
    if (p.relaxed()) {  // the surface is back: an ordinary flight from here
      relaxing_ = false;
      relax_contact_ = -1;
      relax_y_ = 0;
      p.SetSurface(0);
      const S g = m.ContactDisplacement(X_) - m.x0;
      if (!(g > 0)) return EnterContactPhase(k);
      gap_ = multi() ? gaps_[static_cast<size_t>(active_)] : g;
      if (multi()) {
        gaps_[static_cast<size_t>(k)] = g;
        starts_.assign(models_.size(), FlightStart::kGeneric);
        gap_ = gaps_[static_cast<size_t>(active_)];
      }
      flight_start_ = FlightStart::kGeneric;
      return true;
    }
    // A period boundary: the surface's offset carried on.
    relax_y_ = y;
    p.SetSurface(y);
    gap_ = m.ContactDisplacement(X_) - m.x0 - y;
    return true;
  }
}

// A start on or inside a compliant stop: a contact phase when the gap is closed and the body is
// pushed in (or moves in); otherwise the usual classification. True when it decided.
template <class S>
bool Automaton<S>::ClassifyInitialCompliant() {
  int on = -1;
  for (int j = 0; j < static_cast<int>(models_.size()); ++j) {
    if (!Compliant(j)) continue;
    const ModelT<S>& c = M(j);
    const S g = c.ContactDisplacement(X_) - c.x0;
    const S tol = S(System::kStopUlps) * S(std::numeric_limits<double>::epsilon()) *
                  (R::abs(c.x0) + c.shape.cwiseProduct(X_).cwiseAbs().sum());
    if (!(g <= tol)) continue;
    const S v = c.ContactVelocity(V_);
    const bool in = g < -tol || v < 0 || (v == S(0) && c.Reaction(X_, V_, Phase(clock_)) > 0);
    if (in) on = j;
  }
  if (on < 0) return false;
  active_ = on;
  mode_ = Mode::kSticking;
  stick_start_ = StickStart::kGeneric;
  gap_ = 0;
  if (multi())
    for (size_t j = 0; j < models_.size(); ++j) {
      gaps_[j] = models_[j]->ContactDisplacement(X_) - models_[j]->x0;
      starts_[j] = FlightStart::kGeneric;
    }
  return true;
}

template <class S>
void Automaton<S>::NotifyCompliant(ResetKind kind, int contact, const S& rate, const S& surface, bool relaxing) {
  if (opt_.observers.empty()) return;
  Reset r{kind, R::to_double(Phase(clock_)), D(X_, dx_), D(V_, dv_), D(X_, dx2_), D(V_, dv2_), 0.0, 0.0, nullptr,
          nullptr, nullptr, R::to_double(rate), contact};
  r.surface = R::to_double(surface);
  r.relaxing = relaxing;
  for (auto* o : opt_.observers) o->OnReset(r);
}

// Into a checkpoint: the account of the open contact phase of each compliant contact and the
// relaxing flight, so that a resumed run reports the whole phase at its exit and measures its next
// entry to the surface as the run that went through does (docs/compliant.md, docs/output.md).
template <class S>
void Automaton<S>::SaveCompliant(Checkpoint& cp) const {
  cp.relax_contact = relaxing_ ? relax_contact_ : -1;
  cp.relax_surface = relaxing_ ? R::to_double(relax_y_) : 0.0;
  const bool any = std::any_of(compliant_.begin(), compliant_.end(), [](const auto& c) { return c != nullptr; });
  cp.compliant_account.clear();
  if (!any) return;
  for (const CompliantAccount& a : compliant_account_)
    cp.compliant_account.insert(cp.compliant_account.end(), {a.peak, a.peak_time, a.penetration, a.dissipated});
}

template <class S>
void Automaton<S>::RestoreCompliant(const Checkpoint& cp) {
  if (cp.compliant_account.size() == 4 * compliant_account_.size())
    for (size_t j = 0; j < compliant_account_.size(); ++j) {
      const double* a = cp.compliant_account.data() + 4 * j;
      compliant_account_[j] = {a[0], a[1], a[2], a[3]};
    }
  const int k = cp.relax_contact;
  if (mode_ != Mode::kFree || k < 0 || static_cast<size_t>(k) >= compliant_.size() || !compliant_[static_cast<size_t>(k)])
    return;
  if constexpr (std::is_same_v<S, double>) {  // compliant stops run in double only
    relaxing_ = true;
    relax_contact_ = k;
    relax_y_ = cp.relax_surface;
    compliant_[static_cast<size_t>(k)]->SetSurface(cp.relax_surface);
  }
}

// The compliant contact's fields of its entry (stick) and exit (release) events.
template <class S>
void Automaton<S>::CompliantEventLoads(Event& e, int contact) {
  const CompliantAccount& a = compliant_account_[static_cast<size_t>(contact)];
  // Where the body is: the gap's coordinate (the stop's position is not where a compliant contact is).
  e.x_B = R::to_double(M(contact).side * M(contact).ContactDisplacement(X_));
  if (e.kind != EventKind::kRelease) return;
  if (std::isfinite(e.reaction_max) && std::isfinite(a.peak)) {
    e.peak_time = a.peak_time;
    e.penetration_max = a.penetration;
    e.energy_dissipated = a.dissipated;
  }
}

}  // namespace vibro::detail
