"""[[contact]] tables in the modal form (docs/contacts.md, "the modal form") against an independent
truth: the physical-form scene of the same structure.

Every shipped physical-form scene with several contacts (the five data/scenes/contacts_*.toml,
and the impact pair with its contacts in the other order, so that contact 0 is a stop "above") is
rewritten in the modal form here, with NumPy
and none of vibro's code: K φ = λ M φ through a Cholesky factor of M, the modes scaled to contact 0
(σ_0 w_0ᵀψ_i = 1), μ_i = ψ_iᵀMψ_i, T_A,i = ψ_i(A)/μ_i, T_B,i = 1/μ_i, contact j's components
a_j,i = w_jᵀψ_i, the start X = Ψ⁻¹q. Both scenes run through `vibro simulate`; their events must
agree: the same number, kinds and contacts, times within 1e-10 T and gap velocities within
1e-8 (1 + |v|). Why that tolerance: the two runs solve structures whose modal data differ by the
rounding of two eigen-decompositions (NumPy's here, Eigen's in vibro), a few 1e-16 relative;
events move by that times the sensitivity of the motion, which near the end of a chattering
sequence (the landing where the reaction is small) reaches 1e4–1e6. 1e-10 T is the tolerance vibro
is held to against the 40-digit reference (docs/contacts_reference.md); the measured differences
are printed (pytest -s). Not here: the coupled-chattering scene of tests/reference/contacts, whose
chattering sequence with a held pair amplifies any perturbation about 1.9 times per impact
(docs/contacts_reference.md): its two forms measured 8.6e-11 T apart after 80 events, too close
to the tolerance for a test.

data/scenes/contacts_chain2_modal.toml is the same check with the modes derived by hand in closed
form (its comment). The Python package runs it too, and bad modal-form contacts exit 2 naming the
file, line and key, with nothing written.

ctest runs this file as python.modal_contacts (VIBRO_CLI, VIBRO_SCENES, PYTHONPATH set).
"""
import os
import subprocess
import tomllib

import h5py
import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
CLI = os.environ.get("VIBRO_CLI", "")
SCENES = os.environ.get("VIBRO_SCENES", os.path.join(ROOT, "data", "scenes"))

TIME_TOL = 1e-10  # of the forcing period
VEL_TOL = 1e-8    # relative to 1 + |v|


def cli():
    if not CLI:
        pytest.fail("VIBRO_CLI is not set: run the tests through ctest")
    return CLI


# ---------------------------------------------------------------------------------------------
# The modal form by hand (NumPy only)

def direction(c, n):
    """w_j of a [[contact]] table: e_b (dof = b) or e_b − e_a (dofs = [b, a])."""
    w = np.zeros(n)
    if "dof" in c:
        w[c["dof"]] = 1.0
    else:
        b, a = c["dofs"]
        w[b], w[a] = 1.0, -1.0
    return w


def modal_form(doc):
    """The modal-form TOML of a physical-form scene with [[contact]] tables (all modes kept)."""
    st = doc["structure"]
    M = np.array(st["mass"], dtype=float)
    K = np.array(st["stiffness"], dtype=float)
    n = M.shape[0]
    L = np.linalg.cholesky(M)                    # M = L Lᵀ
    Linv = np.linalg.inv(L)
    lam, Y = np.linalg.eigh(Linv @ K @ Linv.T)   # ascending, as vibro lists modes
    Phi = Linv.T @ Y                             # K φ = λ M φ, φᵀMφ = 1
    contacts = doc["contact"]
    sigma = [1.0 if c["side"] == "below" else -1.0 for c in contacts]
    seen = sigma[0] * (direction(contacts[0], n) @ Phi)
    assert np.all(np.abs(seen) > 1e-8 * np.abs(Phi).max(axis=0)), "a mode with a node at contact 0"
    Psi = Phi / seen                             # σ_0 w_0ᵀψ_i = 1
    mu = np.einsum("ij,ik,kj->j", Psi, M, Psi)
    forcing = Psi[st["forcing_dof"], :] / mu
    lines = ["[structure]",
             f"frequencies = {fmt(np.sqrt(lam))}",
             f"forcing = {fmt(forcing)}",
             f"contact = {fmt(1.0 / mu)}"]
    if "damping_ratios" in st:
        lines.append(f"damping_ratios = {fmt(st['damping_ratios'])}")
    for j, c in enumerate(contacts):
        lines.append("[[contact]]")
        if j > 0:
            lines.append(f"modal = {fmt(direction(c, n) @ Psi)}")
        lines += [f'side = "{c["side"]}"', f"position = {float(c['position'])!r}",
                  f"restitution = {float(c['restitution'])!r}"]
    ex = doc["excitation"]
    lines += ["[excitation]", f"amplitude = {float(ex['amplitude'])!r}", f"frequency = {float(ex['frequency'])!r}"]
    ini = doc.get("initial", {})
    if "displacement" in ini:
        lines += ["[initial]", f"time = {float(ini.get('time', 0.0))!r}",
                  f"displacement = {fmt(np.linalg.solve(Psi, np.array(ini['displacement'], dtype=float)))}",
                  f"velocity = {fmt(np.linalg.solve(Psi, np.array(ini['velocity'], dtype=float)))}"]
    lines += ["[run]", f"periods = {int(doc.get('run', {}).get('periods', 200))}"]
    return "\n".join(lines) + "\n"


def fmt(v):
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def physical_text(doc):
    """A physical-form scene dict back to TOML (for the reordered impact pair)."""
    st = doc["structure"]
    lines = ["[structure]", f"mass = {st['mass']}", f"stiffness = {st['stiffness']}",
             f"forcing_dof = {st['forcing_dof']}"]
    if "damping_ratios" in st:
        lines.append(f"damping_ratios = {st['damping_ratios']}")
    for c in doc["contact"]:
        lines.append("[[contact]]")
        lines.append(f"dof = {c['dof']}" if "dof" in c else f"dofs = {c['dofs']}")
        lines += [f'side = "{c["side"]}"', f"position = {c['position']!r}", f"restitution = {c['restitution']!r}"]
    lines += ["[excitation]", f"amplitude = {doc['excitation']['amplitude']!r}",
              f"frequency = {doc['excitation']['frequency']!r}"]
    if "initial" in doc:
        lines += ["[initial]"] + [f"{k} = {v!r}" for k, v in doc["initial"].items()]
    lines += ["[run]", f"periods = {doc.get('run', {}).get('periods', 200)}"]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Running vibro and comparing events

def run(scene, out):
    p = subprocess.run([cli(), "simulate", scene, "--out", out], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout + p.stderr
    with h5py.File(out, "r") as f:
        ev = f["events"]
        events = {k: ev[k][:] for k in ("t", "kind", "contact", "v_before", "v_after", "x_B", "simultaneous")}
        period = float(f.attrs["forcing_period"])
        status = f.attrs["status"]
    return events, period, status, p.stdout


def compare(a, b, period):
    """Largest |Δt|/T and |Δv|/(1 + |v|) of two event lists that must match one to one."""
    assert len(a["t"]) == len(b["t"]), f"{len(a['t'])} events against {len(b['t'])}"
    assert np.array_equal(a["kind"], b["kind"])
    assert np.array_equal(a["contact"], b["contact"])
    assert np.array_equal(a["simultaneous"], b["simultaneous"])
    dt = np.max(np.abs(a["t"] - b["t"])) / period
    dv = max(np.max(np.abs(a[k] - b[k]) / (1 + np.abs(a[k]))) for k in ("v_before", "v_after"))
    dx = np.max(np.abs(a["x_B"] - b["x_B"]) / (1 + np.abs(a["x_B"])))
    return dt, dv, dx


def cases():
    out = []
    for name in ("contacts_two_sided_1dof", "contacts_preload_clearance_1dof", "contacts_chain2",
                 "contacts_impact_pair", "contacts_beam3"):
        out.append(pytest.param(os.path.join(SCENES, name + ".toml"), False, id=name))
    out.append(pytest.param(os.path.join(SCENES, "contacts_impact_pair.toml"), True, id="impact_pair_above_first"))
    return out


@pytest.mark.parametrize("path,reverse", cases())
def test_modal_form_by_hand_gives_the_physical_events(path, reverse, tmp_path):
    with open(path, "rb") as fh:
        doc = tomllib.load(fh)
    physical = path
    if reverse:  # contact 0 a stop above: the modes are scaled to −1 at it (docs/contacts.md)
        doc["contact"] = doc["contact"][::-1]
        assert doc["contact"][0]["side"] == "above"
        physical = str(tmp_path / "physical.toml")
        with open(physical, "w") as fh:
            fh.write(physical_text(doc))
    modal = tmp_path / "modal.toml"
    modal.write_text(modal_form(doc))
    a, period, status_a, _ = run(physical, str(tmp_path / "physical.h5"))
    b, _, status_b, text = run(str(modal), str(tmp_path / "modal.h5"))
    assert status_a == status_b
    assert len(a["t"]) > 20
    dt, dv, dx = compare(a, b, period)
    print(f"{os.path.basename(path)}{' reversed' if reverse else ''}: {len(a['t'])} events, "
          f"max |dt|/T = {dt:.2g}, |dv|/(1+|v|) = {dv:.2g}, |dx_B|/(1+|x_B|) = {dx:.2g}")
    assert dt <= TIME_TOL and dv <= VEL_TOL and dx <= VEL_TOL
    # x_B of an event at contact j is its physical coordinate w_jᵀq in both forms
    assert "a1·X" in text or len(doc["contact"]) == 1


def test_shipped_modal_scene_matches_the_physical_one(tmp_path):
    """contacts_chain2_modal.toml: the modes in closed form (its comment), not computed here."""
    a, period, _, _ = run(os.path.join(SCENES, "contacts_chain2.toml"), str(tmp_path / "p.h5"))
    b, _, _, _ = run(os.path.join(SCENES, "contacts_chain2_modal.toml"), str(tmp_path / "m.h5"))
    dt, dv, dx = compare(a, b, period)
    print(f"contacts_chain2_modal: {len(a['t'])} events, max |dt|/T = {dt:.2g}, |dv| = {dv:.2g}")
    assert dt <= TIME_TOL and dv <= VEL_TOL and dx <= VEL_TOL
    # `vibro plot` draws every gap from the modal coordinates (no mode shapes in the modal form)
    p = subprocess.run([cli(), "plot", "m.h5"], cwd=tmp_path, capture_output=True, text=True, timeout=300,
                       env={**os.environ, "MPLBACKEND": "Agg"})
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "m_gaps.png").stat().st_size > 10000


def test_python_package_runs_the_modal_scene(tmp_path):
    import vibro
    path = os.path.join(SCENES, "contacts_chain2_modal.toml")
    r = vibro.simulate(path)
    assert r.summary["status"] == "ok"
    counts = [c["impacts"] for c in r.summary["contacts"]]
    assert len(counts) == 2 and min(counts) > 0
    assert set(np.unique(r.events["contact"])) == {0, 1}
    # the same events as the CLI's HDF5 file
    b, _, _, _ = run(path, str(tmp_path / "m.h5"))
    assert np.array_equal(r.events["t"], b["t"]) and np.array_equal(r.events["contact"], b["contact"])


# ---------------------------------------------------------------------------------------------
# Bad input: exit 2, file:line and key, nothing written

BASE = """[structure]
frequencies = [1.0, 2.0, 3.0]
forcing = [0.5, 0.3, 0.1]
contact = [0.5, 0.25, 0.125]
{extra}
[[contact]]
side = "below"
position = {p0}
restitution = 0.5

[[contact]]
{second}
side = "{side}"
position = {p1}
restitution = 0.7

[excitation]
amplitude = 1.0
frequency = 1.5
{initial}"""


def bad(tmp_path, second, key, words, line=None, side="below", p0=-0.5, p1=-0.5, extra="", initial=""):
    scene = tmp_path / "bad.toml"
    scene.write_text(BASE.format(second=second, side=side, p0=p0, p1=p1, extra=extra, initial=initial))
    out = tmp_path / "bad.h5"
    p = subprocess.run([cli(), "simulate", str(scene), "--out", str(out)], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 2, p.stdout + p.stderr
    assert key in p.stderr and str(scene) in p.stderr, p.stderr
    if line is not None:
        assert f"{scene}:{line}:" in p.stderr, p.stderr
    for w in words:
        assert w in p.stderr, p.stderr
    assert not out.exists()
    return p.stderr


def test_wrong_length(tmp_path):
    bad(tmp_path, "modal = [1.0, 2.0]", "contact[1].modal", ["length 3 expected", "got 2"], line=12)


def test_missing_modal(tmp_path):
    err = bad(tmp_path, "", "contact[1].modal", ["missing required key"], line=11)
    assert err.count("contact[1].modal") == 1, err


def test_dof_in_the_modal_form(tmp_path):
    bad(tmp_path, "dof = 1", "contact[1].dof", ["modal form names no DOF", "contact[1].modal: missing"], line=12)


def test_modal_on_contact_zero(tmp_path):
    scene = BASE.replace('[[contact]]\nside = "below"\nposition = {p0}',
                         '[[contact]]\nmodal = [1.0, 1.0, 1.0]\nside = "below"\nposition = {p0}', 1)
    path = tmp_path / "c0.toml"
    path.write_text(scene.format(second="modal = [1.0, 0.0, 0.0]", side="below", p0=-0.5, p1=-0.5, extra="",
                                 initial=""))
    p = subprocess.run([cli(), "simulate", str(path), "--out", str(tmp_path / "c0.h5")], capture_output=True,
                       text=True, timeout=60)
    assert p.returncode == 2 and f"{path}:7:" in p.stderr and "contact[0].modal" in p.stderr, p.stderr
    assert "contact of the modal scaling" in p.stderr
    assert not (tmp_path / "c0.h5").exists()


def test_contact_on_no_kept_mode(tmp_path):
    # zero on the two kept modes (structure.modes = 2 keeps ω = 1, 2), non-zero on the dropped one
    bad(tmp_path, "modal = [0.0, 0.0, 1.0]", "contact[1].modal", ["sees a kept mode"], extra="modes = 2")
    bad(tmp_path, "modal = [0.0, 0.0, 0.0]", "contact[1].modal", ["sees a kept mode"])


def test_dependent_contacts(tmp_path):
    # c_1 = 2 c_0 on the same side: dependent
    bad(tmp_path, "modal = [2.0, 2.0, 2.0]", "contact[1].modal", ["dependent", "contacts 0 and 1"], line=12)
    # the opposite side with overlapping stops: g_0 = ΣX + 0.5 ≥ 0 and g_1 = −ΣX/... must leave room
    bad(tmp_path, "modal = [1.0, 1.0, 1.0]", "contact[1].position", ["positive clearance"], side="above",
        p1=-0.6)


def test_two_sided_modal_clearance_is_accepted(tmp_path):
    # ΣX ≥ −0.5 and ΣX ≤ 0.5 (a = 1 above): a two-sided clearance of width 1, which runs
    scene = tmp_path / "ok.toml"
    scene.write_text(BASE.format(second="modal = [1.0, 1.0, 1.0]", side="above", p0=-0.5, p1=0.5, extra="",
                                 initial="[run]\nperiods = 5\n"))
    p = subprocess.run([cli(), "simulate", str(scene)], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert "contact 1  a1·X <= 0.5" in p.stdout, p.stdout


def test_initial_state_violating_a_contact(tmp_path):
    # contact 1 reads q = X_1 ≥ 0.2: X = (0, 0, 0) violates it
    bad(tmp_path, "modal = [1.0, 0.0, 0.0]", "initial.displacement", ["gap of contact 1"], p1=0.2,
        initial="[initial]\ndisplacement = [0.0, 0.0, 0.0]\nvelocity = [0.0, 0.0, 0.0]\n")


def test_cvode_runs_the_modal_scene(tmp_path):
    """CVODE takes several contacts in the modal form too: contacts_chain2_modal.toml at
    rtol 1e-12 against the exact engine, every event in kind and contact, times within 2e-9 T
    (the bound of tests/reference/contacts_cvode_test.cpp on the physical scenes)."""
    scene = os.path.join(SCENES, "contacts_chain2_modal.toml")
    a, period, _, _ = run(scene, str(tmp_path / "exact.h5"))
    cv = tmp_path / "cvode.toml"
    with open(scene) as fh:
        text = fh.read()
    assert "[run]" in text
    cv.write_text(text.replace("[run]", '[run]\nengine = "cvode"\nrtol = 1e-12\natol = 1e-14', 1))
    b, _, status, _ = run(str(cv), str(tmp_path / "cvode.h5"))
    assert status == "ok"
    assert len(a["t"]) == len(b["t"]) > 20
    assert np.array_equal(a["kind"], b["kind"]) and np.array_equal(a["contact"], b["contact"])
    assert np.max(np.abs(a["t"] - b["t"])) / period <= 2e-9
