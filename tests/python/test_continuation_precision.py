"""Bifurcation points located to 1e-12 whatever the step (issue: branch points 1e-9 off).

Truth, derived here with mpmath (40 digits, no vibro code): the two-sided 1-DOF oscillator
x'' + x = a sin(w t), stops at x = -1 and x = +1, restitution r at both. Its symmetric two-impact
orbit is a fixed point of the symmetry-reduced map G (an impact on +1 at phase phi with arrival
speed V -> the next impact on -1, reflected: (phi + w s - pi, -x'(s)), s the flight time); the
period map is G o G, so a multiplier of the orbit is +1 where DG has the eigenvalue -1 (the
pitchfork where the orbit loses its symmetry): det(DG + I) = 0. DG is differentiated numerically
at 40 digits from the propagated flight, a route independent of the closed-form DG of
tests/reference/contacts/closed_forms.py.

The grazing of the preload oscillator x'' + x = a sin(0.8 t), x >= 1, r = 0.8, continued in a from
its two-impact orbit at a = 4 down: the two-impact orbit whose long flight touches x = 1 with zero
speed, six equations in the two impact times and speeds, the touching time and a, solved at 30
digits. It must be located the same whatever the end value and step, and no fold is reported on
the way (the branch approaches the grazing with a vertical tangent, as at a fold, but no
multiplier is at +1 there).

ctest runs this file within python.pytest, with VIBRO_CLI set to the built `vibro`.
"""
import json
import os
import subprocess

import mpmath as mp
import pytest

CLI = os.environ.get("VIBRO_CLI", "")

SCENE = """
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "below"
position = -1.0
restitution = {r!r}
[[contact]]
dof = 0
side = "above"
position = 1.0
restitution = {r!r}
[excitation]
amplitude = {a!r}
frequency = {w!r}
[initial]
time = {t0!r}
displacement = [{x0!r}]
velocity = [{v0!r}]
"""


def vibro(*args):
    if not CLI:
        pytest.skip("VIBRO_CLI is not set")
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=900)
    assert p.returncode == 0, p.stderr
    return p.stdout


def flight(x0, v0, t0, a, w, s):
    """x'' + x = a sin(w t) from (x0, v0) at t0, after s: (x, x')."""
    U = a / (1 - w**2)
    A = x0 - U * mp.sin(w * t0)
    B = v0 - U * w * mp.cos(w * t0)
    return (A * mp.cos(s) + B * mp.sin(s) + U * mp.sin(w * (t0 + s)),
            -A * mp.sin(s) + B * mp.cos(s) + U * w * mp.cos(w * (t0 + s)))


def half_map(phi, V, a, r, w):
    """G: from the impact on +1 at phase phi (arrival speed V) to the next impact on -1, reflected."""
    s = mp.findroot(lambda s: flight(1, -r * V, phi / w, a, w, s)[0] + 1, mp.pi / w)
    return phi + w * s - mp.pi, -flight(1, -r * V, phi / w, a, w, s)[1]


def symmetric_orbit(a, r, w):
    """The fixed point of G with the larger V, from the quadratic of the symmetric orbit
    (U sin phi = 1 - V k1, U cos phi = V k2) refined on G itself."""
    U = a / (1 - w**2)
    k1, k2 = (1 + r) * mp.tan(mp.pi / w / 2) / 2, (1 - r) / (2 * w)
    A2, A1, A0 = k1**2 + k2**2, -2 * k1, 1 - U**2
    V = (-A1 + mp.sqrt(A1**2 - 4 * A2 * A0)) / (2 * A2)
    phi = mp.atan2((1 - k1 * V) / U, k2 * V / U)
    return mp.findroot(lambda p, v: [x - y for x, y in zip(half_map(p, v, a, r, w), (p, v))], (phi, V))


def pitchfork(r, w, lo, hi):
    def g(a):
        phi, V = symmetric_orbit(a, r, w)
        J = mp.matrix(2, 2)
        for j in range(2):
            for i in range(2):
                J[i, j] = mp.diff(lambda x: half_map(*([x, V] if j == 0 else [phi, x]), a, r, w)[i],
                                  phi if j == 0 else V)
        return mp.det(J + mp.eye(2))
    return mp.findroot(g, (mp.mpf(lo), mp.mpf(hi)), solver="anderson")


# (r, w, bracket of the pitchfork amplitude): none of them is a documented parameter set.
CASES = [("0.7", "2.2", 3.5, 3.75), ("0.5", "1.8", 2.75, 3.0), ("0.9", "3.0", 6.25, 6.5)]


@pytest.mark.parametrize("r,w,lo,hi", CASES)
def test_pitchfork_to_1e_12_whatever_the_step(tmp_path, r, w, lo, hi):
    mp.mp.dps = 40
    r_, w_ = mp.mpf(r), mp.mpf(w)
    a_star = pitchfork(r_, w_, lo, hi)
    # Start on the symmetric orbit well below the pitchfork, at a free state a quarter period
    # after its impact on +1.
    a0 = mp.mpf(lo) - mp.mpf("0.5")
    phi, V = symmetric_orbit(a0, r_, w_)
    t0 = phi / w_ + mp.pi / (2 * w_)
    x0, v0 = flight(1, -r_ * V, phi / w_, a0, w_, mp.pi / (2 * w_))
    path = tmp_path / "two_sided.toml"
    path.write_text(SCENE.format(r=float(r_), a=float(a0), w=float(w_), t0=float(t0), x0=float(x0),
                                 v0=float(v0)))
    for args in (["--to", hi + 1.0], ["--to", hi + 8.0, "--step", 1.0], ["--to", hi, "--step", 0.01]):
        b = json.loads(vibro("continue", path, "--param", "excitation.amplitude", "--transient", 0, *args,
                             "--json"))
        bps = [x for x in b["bifurcations"] if x["kind"] == "branch-point"]
        assert len(bps) == 1, (args, b["bifurcations"])
        err = abs(mp.mpf(bps[0]["value"]) - a_star)
        assert err < 1e-12 * a_star, (args, bps[0], mp.nstr(a_star, 20))
        assert bps[0]["bracket"] < 1e-11, (args, bps[0])
        assert not [x for x in b["bifurcations"] if x["kind"] == "fold"], b["bifurcations"]
    # The text prints the value with 17 significant digits and its bracket.
    text = vibro("continue", path, "--param", "excitation.amplitude", "--transient", 0, "--to", hi + 1.0)
    line = next(x for x in text.splitlines() if x.startswith("bifurcation  branch-point"))
    shown = line.split(" = ")[1].split(" ")[0]
    assert len(shown.replace(".", "").lstrip("0")) == 17, line
    assert abs(mp.mpf(shown) - a_star) < 1e-12 * a_star and "(bracket " in line, line


PRELOAD = """
[structure]
frequencies = [1.0]
forcing     = [1.0]
contact     = [1.0]
[stop]
position    = 1.0
restitution = 0.8
[excitation]
amplitude = 4.0
frequency = 0.8
[initial]
time = 9.822882131765398
displacement = [1.251629594415913]
velocity = [1.119605216560821]
"""


def preload_grazing():
    """The amplitude at which the long flight of the two-impact orbit touches x = 1."""
    mp.mp.dps = 30
    r, w = mp.mpf("0.8"), mp.mpf("0.8")
    T = 2 * mp.pi / w

    def fl(x0, v0, t0, a, s):
        return flight(x0, v0, t0, a, w, s)

    def orbit_eqs(t1, v1, t2, v2, a):  # impacts at t1 (arrival v1) and t2 (arrival v2), period T
        x, v = fl(1, -r * v1, t1, a, t2 - t1)
        x2, v3 = fl(1, -r * v2, t2, a, t1 + T - t2)
        return [x - 1, v - v2, x2 - 1, v3 - v1]

    # The orbit just above the grazing, from a rough guess (phases 4.069 and 5.364, speeds -6.17
    # and -4.93), then its long flight's lowest point as the guess of the touching time.
    a0 = mp.mpf("3.9493")
    t1, v1, t2, v2 = mp.findroot(lambda *u: orbit_eqs(*u, a0), (4.069 / w, -6.17, 5.364 / w, -4.93))
    span = t1 + T - t2
    xs = [(fl(1, -r * v2, t2, a0, span * k / 400)[0], t2 + span * k / 400) for k in range(1, 400)]
    gap, tg = min(xs)
    assert 0 < gap - 1 < 1e-3  # a valid orbit close to the grazing
    for k in range(1, 400):  # and the short flight stays above the stop
        assert fl(1, -r * v1, t1, a0, (t2 - t1) * k / 400)[0] > 1

    def eqs(t1, v1, t2, v2, tg, a):
        x, v = fl(1, -r * v2, t2, a, tg - t2)
        return orbit_eqs(t1, v1, t2, v2, a) + [x - 1, v]

    return mp.findroot(lambda *u: eqs(*u), (t1, v1, t2, v2, tg, a0))[5]


def test_preload_grazing_whatever_the_end_value(tmp_path):
    a_g = preload_grazing()
    path = tmp_path / "preload.toml"
    path.write_text(PRELOAD)
    for args in (["--to", 3.6], ["--to", 3.0], ["--to", 3.9, "--step", 0.001], ["--to", 2.0, "--step", 0.5]):
        b = json.loads(vibro("continue", path, "--param", "excitation.amplitude", "--transient", 0, "--kind",
                             "impact", "--period", 1, *args, "--json"))
        # The grazing first; past it the branch goes on along the orbit with the new impact
        # (docs/orbits.md, "Through a grazing"), where later points (a flip) may follow.
        assert [x["kind"] for x in b["bifurcations"]][:1] == ["grazing"], (args, b["bifurcations"])
        g = b["bifurcations"][0]
        assert len(b["bifurcations"]) == 1 or g["through"] in ("past", "back"), (args, g)
        assert abs(mp.mpf(g["value"]) - a_g) < 1e-12 * a_g, (args, g, mp.nstr(a_g, 20))
        assert g["bracket"] < 1e-11, (args, g)


SCENE_E = """
[structure]
mass = [[2.0, 0.0], [0.0, 1.0]]
stiffness = [[4.0, -1.0], [-1.0, 1.0]]
forcing_dof = 0
damping_ratios = [0.02, 0.02]
[[contact]]
dof = 1
side = "below"
position = -0.1
restitution = 0.0
[[contact]]
dof = 1
side = "above"
position = 0.1
restitution = 0.0
[excitation]
amplitude = 0.3
frequency = 0.9
[initial]
displacement = [0.0, 0.0]
velocity = [0.0, 0.0]
"""


def test_one_bifurcation_per_transition(tmp_path):
    """A tube in a loose support (r = 0 at both stops), continued in w from 0.9 down to 0.4: the
    symmetric orbit's landings change on both contacts at once, near w = 0.4953695 (and back near
    0.4211), each reported once, naming both contact sequences; no branch point there, and every
    point's sequence is one of the branch's two."""
    path = tmp_path / "tube.toml"
    path.write_text(SCENE_E)
    b = json.loads(vibro("continue", path, "--param", "excitation.frequency", "--to", 0.4, "--json"))
    near = [x for x in b["bifurcations"] if abs(x["value"] - 0.4953695) < 1e-6]
    assert len(near) == 1, b["bifurcations"]
    assert near[0]["kind"] == "sticking-entry" and "contact sequence" in near[0]["detail"], near[0]
    assert near[0]["bracket"] < 1e-11, near[0]
    assert not [x for x in b["bifurcations"] if x["kind"] == "branch-point"], b["bifurcations"]
    values = sorted(x["value"] for x in b["bifurcations"])
    assert all(v2 - v1 > 1e-6 for v1, v2 in zip(values, values[1:])), values
    seqs = {p["sequence"] for p in b["points"]}
    assert seqs == {"0:impact 0:stick 0:release 1:impact 1:stick 1:release",
                    "0:impact*2 0:stick 0:release 1:impact*2 1:stick 1:release"}, seqs


def test_branch_point_next_to_large_multipliers_whatever_the_step(tmp_path):
    """Scene E (r = 0.7) from w = 0.55 to 0.7: its branch point near 0.57702 lies next to a
    Neimark-Sacker point, where det(DF - I) is a thousand times larger at one end of the step than
    near the root; with --step 0.002 the location fell back to a regula-falsi bracket 3.6e-5 off.
    Every step locates both branch points to 1e-12, with a bracket below 1e-11."""
    path = tmp_path / "tube.toml"
    path.write_text(SCENE_E.replace("restitution = 0.0", "restitution = 0.7").replace("frequency = 0.9",
                                                                                        "frequency = 0.55"))
    found = []
    for step in (0, 0.0005, 0.001, 0.002, 0.003, 0.005):
        b = json.loads(vibro("continue", path, "--param", "excitation.frequency", "--to", 0.7, "--step", step,
                             "--json"))
        bps = sorted((x for x in b["bifurcations"] if x["kind"] == "branch-point"), key=lambda x: x["value"])
        assert len(bps) == 2, (step, b["bifurcations"])
        assert all(x["bracket"] < 1e-11 for x in bps), (step, bps)
        found.append([x["value"] for x in bps])
    for k, ref in enumerate((0.5770188788193565, 0.5967668051586875)):
        values = [f[k] for f in found]
        assert max(values) - min(values) < 1e-12 * ref, values
        assert abs(values[0] - ref) < 1e-12 * ref, values


def test_landing_transition_located_by_its_reaction(tmp_path):
    """The merged r = 0 transition of the tube near w = 0.4953695, located by the landing reaction
    (its root fitted along the branch) and not where the bisection on the events stops short (6.6e-9
    wide before): from above with three steps and from below, where the events' bisection itself
    gets within 1e-15 (a different family of orbits, the other side of the transition), all agree
    to 1e-12."""
    down = tmp_path / "tube.toml"
    down.write_text(SCENE_E)
    up = tmp_path / "tube_up.toml"
    up.write_text(SCENE_E.replace("frequency = 0.9", "frequency = 0.47"))
    values = []
    for path, to, step in ((down, 0.4, 0), (down, 0.4, 0.001), (down, 0.4, 0.005), (up, 0.52, 0)):
        b = json.loads(vibro("continue", path, "--param", "excitation.frequency", "--to", to, "--step", step, "--json"))
        near = [x for x in b["bifurcations"] if abs(x["value"] - 0.4953695) < 1e-6]
        assert len(near) == 1 and near[0]["kind"] == "sticking-entry", (path, step, b["bifurcations"])
        assert near[0]["bracket"] < 1e-11, near[0]
        values.append(near[0]["value"])
    assert max(values) - min(values) < 1e-12 * values[0], values
    # Outside the events' old bracket [0.49536948175, 0.49536948831]: beyond where they stopped.
    assert abs(values[-1] - 0.49536948117) < 1e-10, values


def det_half(a, r, w):
    """det(DG + I) at the symmetric orbit (a, r, w): zero at its pitchforks."""
    phi, V = symmetric_orbit(a, r, w)
    J = mp.matrix(2, 2)
    for j in range(2):
        for i in range(2):
            J[i, j] = mp.diff(lambda x: half_map(*([x, V] if j == 0 else [phi, x]), a, r, w)[i],
                              phi if j == 0 else V)
    return mp.det(J + mp.eye(2))


def test_frequency_pitchforks_whatever_the_step_and_direction(tmp_path):
    """The scene of docs/prove.md (stops at +-1, r = 0.6 at both, a = 3) continued in the forcing
    frequency: its symmetric orbit has pitchforks near w = 1.897 and 1.0519 (det(DG + I) = 0, found
    here at 40 digits). Continued down from w = 2 to 0.6, the first one was reported at 1.8970044
    with the whole step (4.9e-2) as its bracket: the root lay within 4e-3 of the step's end, and the
    fit's samples were not taken past it. Down and up, with several steps, both are located to
    1e-12 with a bracket below 1e-11 that contains the truth."""
    mp.mp.dps = 40
    a, r = mp.mpf(3), mp.mpf("0.6")
    truths = [mp.findroot(lambda w: det_half(a, r, w), (mp.mpf(lo), mp.mpf(hi)), solver="anderson")
              for lo, hi in (("1.89", "1.91"), ("1.04", "1.06"))]
    assert abs(truths[0] - mp.mpf("1.8970038577")) < 1e-10 and abs(truths[1] - mp.mpf("1.0518773851")) < 1e-10

    def scene(w0):  # on the symmetric orbit at w0, a quarter of its half period after the impact on +1
        phi, V = symmetric_orbit(a, r, w0)
        t0 = phi / w0 + mp.pi / (2 * w0)
        x0, v0 = flight(1, -r * V, phi / w0, a, w0, mp.pi / (2 * w0))
        path = tmp_path / f"freq_{float(w0)}.toml"
        path.write_text(SCENE.format(r=float(r), a=float(a), w=float(w0), t0=float(t0), x0=float(x0), v0=float(v0)))
        return path

    down, up = scene(mp.mpf(2)), scene(mp.mpf("0.95"))
    for path, to in ((down, 0.6), (up, 2.1)):
        for step in (0, 0.003, 0.01, 0.02, 0.05, 0.1, 0.2):
            b = json.loads(vibro("continue", path, "--param", "excitation.frequency", "--transient", 0,
                                 "--to", to, "--step", step, "--json"))
            bps = sorted((x for x in b["bifurcations"] if x["kind"] == "branch-point"), key=lambda x: -x["value"])
            assert len(bps) == 2, (to, step, b["bifurcations"])
            for x, truth in zip(bps, truths):
                err = abs(mp.mpf(x["value"]) - truth)
                assert err < 1e-12 * truth, (to, step, x, mp.nstr(truth, 20))
                assert x["bracket"] < 1e-11 and err <= x["bracket"], (to, step, x, mp.nstr(err, 3))
