#!/usr/bin/python3
"""Orbits through simultaneous impacts of decoupled contacts (issue 37; docs/contacts.md, "Periodic
orbits"), through the real `vibro` binary, against the independent mpmath reference
(tests/reference/contacts/reference.py):

    simultaneous_orbits_test.py VIBRO TEST_SCENES_DIR

The scenes are a symmetric 3-DOF chain (unit masses, the middle one forced) with a stop below each
outer mass (W_01 = 0): the outer masses move alike, so both gaps close at one instant on the orbit,
and a perturbation splits that instant into two impacts in either order.

The truth is the reference's own return map z(t0) ↦ z(t0 + qT), Newton on it at 60 digits from
vibro's section, and its Jacobian by central differences of step h = 1e-20. At 60 digits the
reference merges impacts closer than T·1e-40 (its simultaneity window) and resolves gaps above
1e-48: a perturbation of 1e-20 splits the instant by ~1e-20, its second-order gaps are ~1e-40, so the
reference follows the two impacts one after the other, as the true motion does (at 30 digits and
h = 1e-12 the window, T·1e-10, merged them and gave a map with a false kink of 0.7). Truncation
h²·|F'''| ~ 1e-40, rounding 1e-60/h = 1e-40.

* Plastic impacts of both contacts at once, then both held and released
  (contacts_symmetric_plastic_landing.toml) or both leaving at zero velocity
  (contacts_symmetric_plastic_leave.toml), undamped: the map is smooth there (the reference's
  forward and backward quotients agree within 1e-15) and vibro's multipliers equal the eigenvalues
  of the reference Jacobian that are not collapsed.
* A damped chain with r = 0.5 at both (contacts_symmetric_damped_corner.toml): the damping couples
  the two impacts, so the order matters and the map has a corner (the reference's one-sided
  quotients differ by > 1e-3). Its two pieces share their eigenvalues (the corner maps
  antisymmetric perturbations onto symmetric ones only): vibro reports them, equal to the
  reference's central-difference eigenvalues.
* Both outer stops (r = 0) hit at one instant while the middle mass is held on its own stop, and
  leave at once, damped (contacts_symmetric_held_middle.toml): a simultaneous impact beside a held
  contact, at a corner (the reference's one-sided quotients differ by 1.2e-3) whose pieces share
  their eigenvalues. On main the engine stopped the second outer mass with no impact (its closing
  velocity projected away as if it rested beside the held contact) and the multipliers were wrong
  (−0.1976, −0.0207 ± 0.0532i against the reference's −0.0750, 0.0634).
* vibro.orbit (Python) equal to the CLI on the first scene.

Tolerance 5e-13 on the multipliers: vibro's double products over the orbit's events, measured
within 1.2e-13 of the reference.
"""
import json
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

TOL_MU = 5e-13


def orbit(vibro, scene, tmp):
    out = os.path.join(tmp, os.path.basename(scene) + ".h5")
    p = subprocess.run([vibro, "orbit", scene, "--json", "--out", out, "--force"],
                       capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        return None, None, p.stdout + p.stderr
    j = json.loads(p.stdout)
    with h5py.File(out) as f:
        o = f["orbit"].attrs
        phi = np.asarray(f["model"].attrs["mode_shapes"])
        X, V = np.asarray(o["X"]), np.asarray(o["V"])
        sec = (float(o["section_time"]), phi @ X, phi @ V)
    return j, sec, p.stderr


def by_value(mus):
    return sorted(mus, key=lambda z: (round(z.real, 8), z.imag))


def reference(text, t0, q, v, period, h):
    """The reference's fixed point from vibro's section, its Jacobian's eigenvalues and the largest
    difference between its forward and backward difference quotients (a corner's size)."""
    n = len(q)
    eye = [[1 if i == k else 0 for i in range(2 * n)] for k in range(2 * n)]
    z = [mp.mpf(x) for x in list(q) + list(v)]
    z, res, events = H.fixed_point(text, t0, z, period, eye, h, 2)
    cols = H.jacobian(text, t0, z, period, eye, h)
    q0, v0, _ = H.flow(text, t0, z[:n], z[n:], period)
    F0 = q0 + v0
    kink = mp.mpf(0)
    for c in range(2 * n):
        zp = [z[i] + h * eye[c][i] for i in range(2 * n)]
        qp, vp, _ = H.flow(text, t0, zp[:n], zp[n:], period)
        fwd = [(a - b) / h for a, b in zip(qp + vp, F0)]
        kink = max(kink, max(abs(2 * (a - b)) for a, b in zip(fwd, cols[c])))
    J = mp.matrix(2 * n, 2 * n)
    for c in range(2 * n):
        for i in range(2 * n):
            J[i, c] = cols[c][i]
    ev = [complex(e) for e in mp.eig(J, left=False, right=False)]
    simultaneous = any(len(e) > 5 and e[5] for e in events if e[1] == "impact")
    return res, ev, kink, simultaneous


def main():
    vibro = sys.argv[1]
    scenes = sys.argv[2]
    mp.mp.dps = 60
    h = mp.mpf("1e-20")
    cases = (("contacts_symmetric_plastic_landing.toml", "0:stick 1:stick", False),
             ("contacts_symmetric_plastic_leave.toml", None, False),
             ("contacts_symmetric_damped_corner.toml", None, True),
             ("contacts_symmetric_held_middle.toml", "2:stick", True))
    with tempfile.TemporaryDirectory() as tmp:
        for name, sticks, corner in cases:
            path = os.path.join(scenes, name)
            text = open(path).read()
            j, sec, err = orbit(vibro, path, tmp)
            check(f"{name}: orbit converged", j is not None and j["status"] == "converged", (j, err))
            if j is None or j["status"] != "converged":
                continue
            seq = j.get("sequence", "")
            # beside a held contact the two impacts are listed one after the other at the same instant
            check(f"{name}: a simultaneous impact of both stops", "0+1:impact" in seq or "0:impact 1:impact" in seq, seq)
            if sticks:
                check(f"{name}: both stops held after it", sticks in seq, seq)
            check(f"{name}: multipliers exist (no no_jacobian)", "no_jacobian" not in j, j.get("no_jacobian"))
            t0, q, v = sec
            res, ev, kink, simultaneous = reference(text, t0, q, v, j["period"], h)
            print(f"  {name}: reference residual {mp.nstr(res, 3)}, one-sided quotients differ by {mp.nstr(kink, 3)}")
            # Newton on the reference converges quadratically where the map is smooth, linearly at a
            # corner (its central differences average the two pieces' Jacobians): two iterations
            check(f"{name}: reference fixed point", res < mp.mpf("1e-25" if corner else "1e-45"), res)
            check(f"{name}: the reference orbit has the simultaneous impact", simultaneous, None)
            if corner:
                check(f"{name}: the map has a corner there (reference)", kink > mp.mpf("1e-3"), kink)
            else:
                check(f"{name}: the map is smooth there (reference)", kink < mp.mpf("1e-15"), kink)
            got = by_value([complex(a, b) for a, b in j.get("floquet_multipliers", []) if abs(complex(a, b)) > 1e-9])
            want = by_value([e for e in ev if abs(e) > 1e-9])
            dev = max((abs(a - b) for a, b in zip(got, want)), default=float("inf"))
            print(f"  {name}: multipliers {got}: largest deviation from the reference {dev:.2e}")
            check(f"{name}: multipliers = the reference map's eigenvalues (60 digits)",
                  len(got) == len(want) and len(got) > 0 and dev <= TOL_MU, (got, want))

        try:
            import vibro as vb
        except ImportError:
            vb = None
        if vb is not None:
            path = os.path.join(scenes, cases[0][0])
            py = vb.orbit(path)
            j, _, _ = orbit(vibro, path, tmp)
            check("python: vibro.orbit = CLI", j is not None and py["floquet_multipliers"] == j["floquet_multipliers"]
                  and py.get("sequence") == j.get("sequence"), (py, j))
            print(f"  python: vibro.orbit multipliers {py['floquet_multipliers']}")
    finish()


if __name__ == "__main__":
    main()
