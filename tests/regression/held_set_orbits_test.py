#!/usr/bin/python3
"""Orbits held on several contacts (issue 37; docs/contacts.md, "Periodic orbits"), through the real
`vibro` binary, against the independent mpmath reference (tests/reference/contacts/reference.py):

    held_set_orbits_test.py VIBRO TEST_SCENES_DIR

The truth is the reference's own return map z(t0) ↦ z(t0 + qT) in physical coordinates (q, q̇),
at vibro's section time, differentiated by central differences of step h = 1e-12 at 30 digits
(truncation h²·|F'''| ≈ 1e-24, rounding 1e-30/h = 1e-18: the quotients are exact to ~1e-17 where
the map is smooth), after Newton on the reference map itself (so the fixed point is the reference's,
not vibro's). vibro computes its multipliers in double from closed-form flows and saltations: each
matrix entry carries a few ulps per event, so 1e-9 absolute leaves three orders of margin on
these O(1) orbits with 4-6 events per period.

* Scene F (tests/scenes/contacts_stacked_cradle.toml): `vibro orbit` finds the period-2 orbit
  (its section in a phase held on contact 0); its two multipliers equal the eigenvalues of the
  reference map restricted to the held manifold {q0 = 0.3, q̇0 = 0} within 1e-9, the two constrained
  ones are absent, |μ1 μ2| = 0.8⁸ (four impacts of r = 0.8, undamped); its impact phases and
  speeds equal those of the reference orbit at 60 digits within 1e-10.
* Scene A (tests/scenes/contacts_quad_start_two_stops.toml): the orbit is held on both stops at
  once for part of its period, which holds every direction of the 2-DOF structure: the map is
  locally constant (the reference map's Jacobian is 0 within 1e-9), and vibro reports a Jacobian,
  no multiplier left after the 2·2 collapsed ones, stable; its stick and release phases equal
  the reference's within 1e-10.
* A 3-DOF chain whose first two masses are held on stops at once while the third moves
  (tests/scenes/contacts_two_held_chain.toml): the multipliers that are not collapsed equal those
  of the reference's full Jacobian within 1e-9 (both sides through the held flow on the set, the
  plastic entry onto it and the release from it).
* The sticking fraction of each (docs/output.md: the time with at least one contact held, per
  orbit period): the measure of the union of the reference orbit's held intervals over its q
  periods, within 1e-9 — 1 for scene F, whose contact 0 is held throughout (it was 0.000000), and
  the overlapping phases of two contacts counted once for A and the chain; `vibro simulate`'s
  attractor line settled on scene F says 1.000000 too.
* The same from Python (vibro.orbit) when the package is importable: equal to the CLI's.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import h5py
import mpmath as mp
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from checks import check, finish  # noqa: E402
import held_set_orbits_ref as H  # noqa: E402

TOL_MU = 1e-9
TOL_EVENT = 1e-10


def orbit(vibro, scene, tmp, *args):
    out = os.path.join(tmp, os.path.basename(scene) + ".h5")
    p = subprocess.run([vibro, "orbit", scene, "--json", "--out", out, "--force", *args],
                       capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        return None, None, p.stdout + p.stderr
    j = json.loads(p.stdout)
    with h5py.File(out) as f:
        o = f["orbit"].attrs
        phi = np.asarray(f["model"].attrs["mode_shapes"])
        X, V = np.asarray(o["X"]), np.asarray(o["V"])
        # the mode shapes ψ_i are the columns of /model@mode_shapes (DOF by row): q = Σ X_i ψ_i
        sec = (float(o["section_time"]), phi @ X, phi @ V)
    return j, sec, p.stderr


def mus(j):
    return sorted((complex(a, b) for a, b in j["floquet_multipliers"]), key=lambda z: (-abs(z), z.imag))


def close_sets(a, b, tol):
    a, b = sorted(a, key=lambda z: (round(z.real, 6), z.imag)), sorted(b, key=lambda z: (round(z.real, 6), z.imag))
    if len(a) == len(b) and a:
        print(f"  multipliers {a}: largest deviation from the reference {max(abs(x - y) for x, y in zip(a, b)):.2e}")
    return len(a) == len(b) and all(abs(x - y) <= tol for x, y in zip(a, b)), a, b


def held_fraction(events, t0, span):
    """The time with at least one contact held over [t0, t0 + span], / span, from the reference's
    events (stick adds a contact; release, leave and liftoff take it away)."""
    held, since, total = set(), None, mp.mpf(0)
    for e in sorted(events, key=lambda e: e[0]):
        t, kind, c = e[0], e[1], e[2]
        if kind == "stick":
            if not held:
                since = t
            held.add(c)
        elif kind in ("release", "leave", "liftoff") and c in held:
            held.discard(c)
            if not held:
                total += t - since
    if held:
        total += t0 + span - since
    return float(total / span)


def main():
    vibro_exe = vibro = sys.argv[1]
    scenes = sys.argv[2]
    mp.mp.dps = 30
    h = mp.mpf("1e-12")
    with tempfile.TemporaryDirectory() as tmp:
        # ---- Scene F: the stacked cradle, period 2, section held on contact 0
        path = os.path.join(scenes, "contacts_stacked_cradle.toml")
        text = open(path).read()
        j, sec, err = orbit(vibro, path, tmp)
        check("F: orbit converged", j is not None and j["status"] == "converged", (j, err))
        if j is not None and j["status"] == "converged":
            check("F: period 2", j["period"] == 2 and j["least_period"] == 2, j)
            t0, q, v = sec
            check("F: section held on contact 0", abs(q[0] - 0.3) < 1e-12 and abs(v[0]) < 1e-12, sec)
            z = [mp.mpf(x) for x in list(q) + list(v)]
            dirs = [[0, 1, 0, 0], [0, 0, 0, 1]]  # the held manifold q0 = 0.3, q̇0 = 0
            z, res, _ = H.fixed_point(text, t0, z, 2, dirs, h)
            check("F: reference fixed point", res < mp.mpf("1e-20"), res)
            ref_mu, _ = H.reduced_multipliers(text, t0, z, 2, dirs, h)
            ref_mu = [complex(x) for x in ref_mu]
            ok, a, b = close_sets(mus(j), ref_mu, TOL_MU)
            check("F: multipliers = reference map's on the held manifold", ok, (a, b))
            check("F: |μ1 μ2| = 0.8^8", abs(abs(np.prod(mus(j))) - 0.8 ** 8) < 1e-12, mus(j))
            check("F: stable", j["stable"] is True, j["stable"])
            check("F: sticking fraction 1 (contact 0 held throughout)", abs(j["sticking_fraction"] - 1) < 1e-12,
                  j["sticking_fraction"])
            # events at 60 digits: the reference orbit, Newton again at 60 digits from the 30-digit one
            with mp.workdps(60):
                z60, res60, events = H.fixed_point(text, t0, [mp.mpf(x) for x in z], 2, dirs, mp.mpf("1e-25"), 2)
                T = 2 * mp.pi / mp.mpf("1.5")
                w = mp.mpf("1.5")
                ref_imp = sorted((float(mp.fmod(w * e[0], 2 * mp.pi)), e[2], float(e[3]))
                                 for e in events if e[1] == "impact")
                ref_sf = held_fraction(events, mp.mpf(t0), 2 * T)
            check("F: sticking fraction = the reference orbit's held time", abs(j["sticking_fraction"] - ref_sf) < 1e-9,
                  (j["sticking_fraction"], ref_sf))
            p = subprocess.run([vibro, "simulate", path, "--set", "run.periods=300"], capture_output=True, text=True,
                               timeout=600)
            line = [s for s in p.stdout.splitlines() if s.startswith("attractor")]
            check("F: simulate's attractor line says sticking fraction 1.000000",
                  len(line) == 1 and "sticking fraction 1.000000" in line[0], (line, p.stderr[-300:]))
            check("F: reference fixed point at 60 digits", res60 < mp.mpf("1e-40"), res60)
            got = sorted(zip(j["impact_phases"], j["impact_contacts"], j["impact_velocities"]))
            check("F: four impacts of contact 1", len(got) == 4 and all(c == 1 for _, c, _ in got), got)
            # vibro's phases run over the q periods of the orbit (ωt mod 2πq): compared mod 2π
            got = sorted((math.fmod(p, 2 * math.pi), c, v) for p, c, v in got)
            if len(got) == len(ref_imp):
                dphi = max(abs(a[0] - b[0]) for a, b in zip(got, ref_imp))
                dv = max(abs(a[2] - b[2]) for a, b in zip(got, ref_imp))
                print(f"  F: impacts: largest phase deviation {dphi:.2e}, speed deviation {dv:.2e}")
                check("F: impact phases = 60-digit reference", dphi < TOL_EVENT, (got, ref_imp))
                check("F: impact speeds (ġ before) = 60-digit reference", dv < TOL_EVENT, (got, ref_imp))
            else:
                check("F: impact count = reference", False, (got, ref_imp))

        # ---- Scene A: held on both stops at once, superstable
        path = os.path.join(scenes, "contacts_quad_start_two_stops.toml")
        text = open(path).read()
        j, sec, err = orbit(vibro, path, tmp)
        check("A: orbit converged", j is not None and j["status"] == "converged", (j, err))
        if j is not None and j["status"] == "converged":
            check("A: no no_jacobian", "no_jacobian" not in j, j.get("no_jacobian"))
            # both stops held at once hold every direction of a 2-DOF structure: none left
            check("A: no multiplier left (superstable)", j["floquet_multipliers"] == [], j["floquet_multipliers"])
            check("A: stable", j["stable"] is True, j["stable"])
            t0, q, v = sec
            z = [mp.mpf(x) for x in list(q) + list(v)]
            eye = [[1 if i == k else 0 for i in range(4)] for k in range(4)]
            z, res, events = H.fixed_point(text, t0, z, 1, eye, h, 1)
            cols = H.jacobian(text, t0, z, 1, eye, h)
            big = max(abs(x) for c in cols for x in c)
            print(f"  A: largest entry of the reference map's Jacobian {float(big):.2e}")
            check("A: reference Jacobian is 0", big < TOL_MU, big)
            w = mp.mpf("0.5")
            ref_st = sorted(float(mp.fmod(w * e[0], 2 * mp.pi)) for e in events if e[1] in ("stick", "release", "leave"))
            got_st = sorted(math.fmod(x, 2 * math.pi) for ph in j["stick_phases"] for x in ph)
            ok = len(ref_st) == len(got_st) and max(abs(a - b) for a, b in zip(ref_st, got_st)) < TOL_EVENT
            check("A: stick phases = reference", ok, (got_st, ref_st))
            ref_sf = held_fraction(events, mp.mpf(t0), 2 * mp.pi / w)
            check("A: sticking fraction = the reference orbit's held time (both stops counted once)",
                  abs(j["sticking_fraction"] - ref_sf) < 1e-9, (j["sticking_fraction"], ref_sf))

        # ---- 3-DOF chain: two stops held at once, one mass free
        path = os.path.join(scenes, "contacts_two_held_chain.toml")
        text = open(path).read()
        j, sec, err = orbit(vibro, path, tmp)
        check("chain: orbit converged", j is not None and j["status"] == "converged", (j, err))
        if j is not None and j["status"] == "converged":
            check("chain: no no_jacobian", "no_jacobian" not in j, j.get("no_jacobian"))
            seq = j.get("sequence", "")
            t0, q, v = sec
            z = [mp.mpf(x) for x in list(q) + list(v)]
            n = len(q)
            eye = [[1 if i == k else 0 for i in range(2 * n)] for k in range(2 * n)]
            z, res, events = H.fixed_point(text, t0, z, j["period"], eye, h, 2)
            check("chain: reference fixed point", res < mp.mpf("1e-20"), res)
            held = {}
            both = False
            for e in events:
                if e[1] == "stick":
                    held[e[2]] = True
                elif e[1] in ("release", "leave"):
                    held.pop(e[2], None)
                both = both or len(held) >= 2
            check("chain: the reference orbit holds two contacts at once", both, seq)
            ref_sf = held_fraction(events, mp.mpf(t0), j["period"] * 2 * mp.pi / mp.mpf("0.5"))
            check("chain: sticking fraction = the reference orbit's held time (overlaps counted once)",
                  abs(j["sticking_fraction"] - ref_sf) < 1e-9, (j["sticking_fraction"], ref_sf))
            ref_mu, _ = H.reduced_multipliers(text, t0, z, j["period"], eye, h)
            ref_mu = [complex(x) for x in ref_mu if abs(x) > 1e-12]
            got = [m for m in mus(j) if abs(m) > 1e-12]
            ok, a, b = close_sets(got, ref_mu, TOL_MU)
            check("chain: non-zero multipliers = reference", ok, (a, b))

        # ---- Chattering into an accumulation point beside a held contact (both held at once after it):
        # the multipliers through the jump's tangent map against the reference's full Jacobian. The
        # reference follows the chattering impacts until its tail is within 1e-25 T (the true map);
        # vibro jumps to its predicted accumulation point and differentiates that jump (measured:
        # within 5.4e-14 on the cradle, 3.4e-13 on the damped chain): TOL_MU.
        for name, label in (("contacts_cradle_chatter.toml", "cradle+1"), ("contacts_held_chain_chatter.toml",
                                                                          "damped chain")):
            path = os.path.join(scenes, name)
            text = open(path).read()
            j, sec, err = orbit(vibro, path, tmp)
            check(f"{label}: orbit converged", j is not None and j["status"] == "converged", (j, err))
            if j is None or j["status"] != "converged":
                continue
            check(f"{label}: multipliers exist (no no_jacobian)", "no_jacobian" not in j, j.get("no_jacobian"))
            check(f"{label}: a chattering accumulation beside a held contact",
                  "1:accumulation" in j.get("sequence", ""), j.get("sequence"))
            t0, q, v = sec
            z = [mp.mpf(x) for x in list(q) + list(v)]
            n = len(q)
            eye = [[1 if i == k else 0 for i in range(2 * n)] for k in range(2 * n)]
            z, res, events = H.fixed_point(text, t0, z, j["period"], eye, h, 2)
            check(f"{label}: reference fixed point", res < mp.mpf("1e-20"), res)
            both, held = False, set()
            for e in sorted(events, key=lambda e: e[0]):
                if e[1] == "stick":
                    held.add(e[2])
                elif e[1] in ("release", "leave", "liftoff"):
                    held.discard(e[2])
                both = both or len(held) >= 2
            check(f"{label}: the reference orbit holds both contacts at once", both, events[-6:])
            ref_mu, _ = H.reduced_multipliers(text, t0, z, j["period"], eye, h)
            ref_mu = [complex(x) for x in ref_mu if abs(x) > 1e-12]
            got = [m for m in mus(j) if abs(m) > 1e-12]
            ok, a, b = close_sets(got, ref_mu, TOL_MU)
            check(f"{label}: multipliers = the reference map's (central differences, 30 digits)", ok, (a, b))

        # ---- Lyapunov spectra of runs that settle on these orbits: every exponent of a multiplier,
        # ln|μ|/(qT), inside its interval; the held directions collapsed (−∞ or far below), not 0
        for name, q, w in (("contacts_stacked_cradle.toml", 2, 1.5), ("contacts_two_held_chain.toml", 1, 0.5)):
            path = os.path.join(scenes, name)
            j, _, _ = orbit(vibro_exe, path, tmp)
            p = subprocess.run([vibro_exe, "simulate", path, "--json", "--set", "run.periods=400"],
                               capture_output=True, text=True, timeout=600)
            ly = json.loads(p.stdout) if p.returncode == 0 else {}
            ex, ci = ly.get("lyapunov_exponents", []), ly.get("lyapunov_ci", [])
            T = 2 * math.pi / w
            want = sorted({round(math.log(abs(complex(a, b))) / (q * T), 12) for a, b in j["floquet_multipliers"]})
            top = [(e, c) for e, c in zip(ex, ci) if e is not None][:2]
            inside = lambda e, c: c[0] <= want[0] <= c[1] if isinstance(c, list) else abs(e - want[0]) <= c
            ok = len(top) == 2 and len(want) == 1 and all(inside(e, c) for e, c in top)
            print(f"  {name}: Lyapunov {top}, ln|μ|/(qT) = {want}")
            check(f"{name}: Lyapunov exponents contain ln|μ|/(qT)", ok, (ex, ci, want, ly.get("lyapunov_undefined")))
            rest = [e for e in ex[2:]]
            check(f"{name}: the held directions collapse", all(e is None or e < -1 for e in rest), ex)

        # ---- Python: vibro.orbit gives the CLI's answer
        try:
            import vibro
        except ImportError:
            vibro = None
        if vibro is not None:
            path = os.path.join(scenes, "contacts_stacked_cradle.toml")
            py = vibro.orbit(path)
            j, _, _ = orbit(sys.argv[1], path, tmp)
            check("python: vibro.orbit = CLI", py["floquet_multipliers"] == j["floquet_multipliers"] and
                  py["impact_phases"] == j["impact_phases"], (py, j))
    finish()


if __name__ == "__main__":
    main()
