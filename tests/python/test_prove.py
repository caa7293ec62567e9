"""vibro.prove mirrors `vibro prove` (docs/prove.md): the same dict as the command's --json, the
certificate that the independent checker confirms, and the same errors."""
import json
import os
import subprocess
import sys

import pytest

import vibro
from conftest import CLI, SCENES

CHECKER = os.path.join(os.path.dirname(__file__), "..", "..", "scripts", "vibro_check_proof.py")


def test_prove_matches_the_command_and_its_certificate_is_confirmed(tmp_path):
    scene = os.path.join(SCENES, "fig05_coexistence.toml")
    cert = tmp_path / "fig05.json"
    r = vibro.prove(scene, kind="impact", out=cert)
    p = subprocess.run([CLI, "prove", scene, "--kind", "impact", "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert r == json.loads(p.stdout)
    assert r["verdict"] == "proven" and r["stability"] == "stable" and r["box_width"] <= 1e-10
    c = subprocess.run([sys.executable, CHECKER, str(cert)], capture_output=True, text=True, timeout=600)
    assert c.returncode == 0, c.stdout + c.stderr


def test_prove_proves_a_chattering_orbit_and_says_why_it_does_not_prove_another():
    r = vibro.prove(os.path.join(SCENES, "fig05_coexistence.toml"))
    assert r["verdict"] == "proven" and r["sequence"][-2:] == ["accumulation", "stick"]
    r = vibro.prove(os.path.join(SCENES, "chain3.toml"))  # 3 modes held at a plastic stop (r = 0)
    assert r["verdict"] == "proven" and r["sequence"] == ["release", "impact", "stick"] and len(r["multipliers"]) == 4
    r = vibro.prove(os.path.join(SCENES, "chain2.toml"))  # 2 modes, r = 0.5: chattering
    assert r["verdict"] == "not-proven" and "chattering (r > 0) of a model with more than one mode" in r["reason"]


def test_prove_proves_a_damped_two_contact_orbit_and_refuses_a_bad_period(tmp_path):
    """Damped models and several contacts (issue 40): the tube in its two-sided loose support, as
    the command proves it; its certificate confirmed."""
    scene = os.path.join(SCENES, "tube_loose_support.toml")
    cert = tmp_path / "tube.json"
    r = vibro.prove(scene, out=cert)
    p = subprocess.run([CLI, "prove", scene, "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert r == json.loads(p.stdout)
    assert r["verdict"] == "proven" and sorted(e["contact"] for e in r["events"]) == [0, 1]
    c = subprocess.run([sys.executable, CHECKER, str(cert)], capture_output=True, text=True, timeout=600)
    assert c.returncode == 0, c.stdout + c.stderr
    r = vibro.prove(os.path.join(SCENES, "chain2_damped.toml"))
    assert r["verdict"] == "not-proven" and "chattering (r > 0) of a model with more than one mode" in r["reason"]
    with pytest.raises(ValueError):
        vibro.prove(os.path.join(SCENES, "fig04_subharmonic.toml"), period=-1)



def test_ctrl_c_during_the_transient_of_a_proof_raises_keyboard_interrupt(tmp_path):
    """vibro.prove(scene, transient=10**7) ignored Ctrl-C for 40 s and more (issue 38): now
    KeyboardInterrupt, nothing proven, the certificate not written. The child is signalled once it
    is observably inside the call (test_stop_requests.py's harness)."""
    from test_stop_requests import LIMIT, _interrupt
    code, out, err, elapsed = _interrupt("vibro.prove(scene, transient=10**7, out='c.json')", tmp_path)
    assert code == 130 and "KeyboardInterrupt: vibro: proof interrupted" in out, (out, err)
    assert not (tmp_path / "c.json").exists()
    print(f"KeyboardInterrupt {elapsed:.3f} s after SIGINT")
    assert elapsed < LIMIT, f"KeyboardInterrupt {elapsed:.2f} s after SIGINT"

def test_the_time_limit_covers_the_transient():
    """time_limit bounds the whole call, the transient included (it ran on past 120 s)."""
    code = ("import vibro, json; print(json.dumps(vibro.prove(%r, transient=10**7, time_limit=1)))"
            % os.path.join(SCENES, "fig05_coexistence.toml"))
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    r = json.loads(p.stdout)
    assert r["verdict"] == "not-proven" and "time limit of 1 s" in r["reason"] and "orbit search" in r["reason"]


def test_prove_bifurcation_matches_the_command_and_its_certificate_is_confirmed(tmp_path):
    """vibro.prove_bifurcation is `vibro prove --bifurcation KIND:KEY=VALUE --json`: the pitchfork of
    the symmetric two-sided oscillator (r = 0.6, ω = 2; its amplitude 3.2860503573579958, the closed
    form of docs/prove.md "Bifurcation points"), enclosed within 1e-10; 1e-9 past it nothing."""
    scene = os.path.join(SCENES, "contacts_two_sided_1dof.toml")
    text = open(scene).read().replace("restitution = 0.5", "restitution = 0.6").replace("frequency = 0.8",
                                                                                        "frequency = 2.0")
    path = tmp_path / "two_sided.toml"
    path.write_text(text)
    cert = tmp_path / "pitchfork.json"
    r = vibro.prove_bifurcation(str(path), "branch-point", "excitation.amplitude", 3.2860503573579969, out=cert)
    p = subprocess.run([CLI, "prove", str(path), "--bifurcation", "branch-point:excitation.amplitude=3.2860503573579969",
                        "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert r == json.loads(p.stdout)
    lo, hi = (float(x) for x in r["interval"])
    assert r["verdict"] == "proven" and lo <= 3.2860503573579958 <= hi and hi - lo <= 1e-10
    c = subprocess.run([sys.executable, CHECKER, str(cert)], capture_output=True, text=True, timeout=600)
    assert c.returncode == 0, c.stdout + c.stderr
    r = vibro.prove_bifurcation(str(path), "branch-point", "excitation.amplitude", 3.2860503583579958)
    assert r["verdict"] == "not-proven" and "no pitchfork is proven" in r["reason"]


def test_prove_segment_in_the_frequency_contains_the_50_digit_orbits(tmp_path):
    """vibro.prove_segment (docs/prove.md "Segments in the frequency"): the tube over ω = 0.9 to
    0.901, each end's orbit the one the scene's start reaches; every piece proven, the certificates
    confirmed, and the orbit at the ends and the middle of each piece (Newton at 50 digits on the
    shooting map of tests/regression/prove_truth.py, nothing from vibro's sources) in its enclosures."""
    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "regression"))
    import copy

    from mpmath import mp, mpf
    from prove_truth import inside, orbit_truth
    mp.dps = 50
    scene = os.path.join(SCENES, "tube_loose_support.toml")
    cert = tmp_path / "segment.json"
    pieces = vibro.prove_segment(scene, "excitation.frequency", 0.9, 0.901, out=cert)
    assert pieces and all(p["verdict"] == "proven" for p in pieces), [p["reason"][:200] for p in pieces]
    assert all(p["reason"].startswith("for every frequency in [") for p in pieces)
    c = subprocess.run([sys.executable, CHECKER, str(cert)], capture_output=True, text=True, timeout=900)
    assert c.returncode == 0, c.stdout + c.stderr
    certs = json.load(open(cert))["certificates"]
    assert len(certs) == len(pieces) and all("tangent" in x for x in certs)
    # Stability along the segment (docs/prove.md "Stability along a segment"): every piece stable, and
    # the 50-digit spectral radius at each sub-piece's middle below that sub-piece's bound.
    assert all(p["stability"] == "stable" and not p["multipliers"] for p in pieces)
    for x in certs:
        for sub in x["spectral_bound"][::max(1, len(x["spectral_bound"]) // 3)]:
            a, z = (mpf(v.strip()) for v in sub["interval"][1:-1].split(","))
            y = copy.deepcopy(x)
            y["model"]["frequency"] = mp.nstr((a + z) / 2, 30)
            assert max(abs(mu) for mu in orbit_truth(y)["multipliers"]) <= sub["bound"] < 1
    for x, s in zip(certs, pieces):
        a, z = (mpf(v.strip()) for v in x["model"]["frequency"][1:-1].split(","))
        for value in (a, (a + z) / 2, z):
            y = copy.deepcopy(x)
            y["model"]["frequency"] = mp.nstr(value, 30)
            tr = orbit_truth(y)
            for j, e in enumerate(s["events"]):
                assert inside(tr["times"][j], e["time"]) and inside(tr["vbefore"][j], e["velocity_before"])
            t0, X0, V0 = tr["section"]
            assert inside(t0, s["section"]["time"]) and all(inside(v, p) for v, p in zip(V0, s["section"]["V"]))
    with pytest.raises(ValueError):  # lo < hi
        vibro.prove_segment(scene, "excitation.frequency", 0.901, 0.9)
