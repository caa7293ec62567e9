"""Resuming and extending runs from Python (docs/python.md): `simulate(out=..., extend=N)` and
`simulate(out=..., resume=True)` go through the command line's code (src/frontend/run_output.cpp),
so the file ends equal, to the bit, to an uninterrupted run of the total length and to the file the
CLI's --extend / --resume leaves; `basin(out=..., resume=True)` likewise. Refusals are ValueErrors
naming the argument, and leave the file as it was."""
import hashlib
import os
import subprocess

import h5py
import numpy as np
import pytest

import vibro

from conftest import CLI, SCENES

FIG8 = os.path.join(SCENES, "fig08_preload.toml")
# Attributes that record how and when a file was written, not what the run computed.
INVOCATION = {"created", "command_line", "options"}


def contents(path):
    """Every dataset (dtype, shape, bytes) and attribute of the file, by path."""
    datasets, attrs = {}, {}
    with h5py.File(path, "r") as f:
        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                datasets["/" + name] = (str(obj.dtype), obj.shape, np.ascontiguousarray(obj[()]).tobytes())
            attrs["/" + name] = {k: np.asarray(v).tobytes() if not isinstance(v, (str, bytes)) else v
                                 for k, v in obj.attrs.items()}
        attrs["/"] = {k: np.asarray(v).tobytes() if not isinstance(v, (str, bytes)) else v
                      for k, v in f.attrs.items() if k not in INVOCATION}
        f.visititems(visit)
    return datasets, attrs


def carried(path):
    """Root attributes an extension cannot reproduce (extend_test.py): CVODE work counters, and the
    chattering counters unless the checkpoint carries them."""
    with h5py.File(path, "r") as f:
        skip = {k for k in f.attrs if k.startswith("cvode_") and k != "cvode_method"}
        if "chatter_accumulations_predicted" not in f["checkpoint"].attrs:
            skip |= {k for k in f.attrs if k.startswith("chatter_")}
    return skip


def assert_same_bits(reference, path):
    rd, ra = contents(reference)
    pd, pa = contents(path)
    assert sorted(rd) == sorted(pd)
    for name in rd:
        assert rd[name] == pd[name], f"{name} differs"
    skip = carried(path)
    assert sorted(ra) == sorted(pa)
    for group in ra:
        a = {k: v for k, v in ra[group].items() if group != "/" or k not in skip}
        b = {k: v for k, v in pa[group].items() if group != "/" or k not in skip}
        assert a == b, (group, sorted(k for k in set(a) | set(b) if a.get(k) != b.get(k)))


def digest(path):
    with open(path, "rb") as fh:
        return hashlib.sha256(fh.read()).hexdigest()


def cli(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=600)


@pytest.mark.parametrize("engine, first, more", [("exact", 200, 300), ("cvode", 60, 90)])
def test_extend_equals_an_uninterrupted_run_and_the_cli(engine, first, more, tmp_path):
    sets = {"run.engine": engine}
    ref, ext, by_cli = (str(tmp_path / n) for n in ("ref.h5", "ext.h5", "cli.h5"))
    whole = vibro.simulate(vibro.load_scene(FIG8, set={**sets, "run.periods": first + more}), out=ref)
    vibro.simulate(vibro.load_scene(FIG8, set={**sets, "run.periods": first}), out=ext)
    # The scene given says run.periods = first: an extension takes the file's periods + N.
    r = vibro.simulate(vibro.load_scene(FIG8, set={**sets, "run.periods": first}), out=ext, extend=more)
    assert r.summary["attractor"] == whole.summary["attractor"]
    assert r.summary["t_end"] == whole.summary["t_end"] and r.summary["counts"] == whole.summary["counts"]
    # The arrays hold what this call computed: the periods first..first + more.
    assert r.section["t"][0] > whole.section["t"][first - 1]
    assert np.array_equal(r.section["X"], whole.section["X"][-len(r.section):])
    assert_same_bits(ref, ext)
    p = cli("simulate", FIG8, "--set", f'run.engine="{engine}"', "--set", f"run.periods={first}", "--out", by_cli)
    assert p.returncode == 0, p.stderr
    p = cli("simulate", FIG8, "--set", f'run.engine="{engine}"', "--out", by_cli, "--extend", str(more))
    assert p.returncode == 0, p.stderr
    assert_same_bits(by_cli, ext)
    with h5py.File(ext, "r") as f:
        assert f.attrs["periods"] == first + more
        assert "extend=" in f.attrs["command_line"]


class Stop(Exception):
    pass


def stop_after(periods):
    def report(done, total):
        if done >= periods:
            raise Stop(f"stopped at {done} of {total}")
    return report


def test_a_run_stopped_by_its_progress_callback_resumes_to_the_bits_of_an_uninterrupted_run(tmp_path):
    total = 60000
    scene = vibro.load_scene(FIG8, set={"run.periods": total, "run.samples_per_period": 4})
    ref, path = str(tmp_path / "ref.h5"), str(tmp_path / "run.h5")
    vibro.simulate(scene, out=ref)
    with pytest.raises(Stop):
        vibro.simulate(scene, out=path, progress=stop_after(1000))
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == "interrupted"
        stopped = int(f["checkpoint"].attrs["period"])
    assert 0 < stopped < total
    seen = []
    r = vibro.simulate(scene, out=path, resume=True, progress=lambda d, n: seen.append((d, n)))
    assert r.summary["status"] == "ok"
    assert seen[-1] == (total, total) and all(stopped < d <= total for d, _ in seen)
    assert_same_bits(ref, path)


def test_basin_resume_equals_an_uninterrupted_study(tmp_path):
    # 30 000 cells: progress is reported at most every 0.1 s, so the study must outlast the first
    # report (about 1.5 s on one thread of an idle machine) to be stopped by it.
    scene = vibro.load_scene(os.path.join(SCENES, "fig05_coexistence.toml"))
    ref, path = str(tmp_path / "ref.h5"), str(tmp_path / "basin.h5")
    whole = vibro.basin(scene, grid=(200, 150), threads=1, out=ref)
    with pytest.raises(Stop):
        vibro.basin(scene, grid=(200, 150), threads=1, out=path, progress=stop_after(1))
    with h5py.File(path, "r") as f:
        assert f.attrs["status"] == "interrupted"
        assert (f["basin/labels"][()] == -3).any()
        # An interrupted study measures no Lyapunov exponents; its resumption does.
        assert (f["attractors/chaotic"][()] == -1).all()
    with pytest.raises(ValueError, match="cannot resume: grid is 200,150 in the file but 200,151 here"):
        vibro.basin(scene, grid=(200, 151), threads=1, out=path, resume=True)
    resumed = vibro.basin(scene, grid=(200, 150), threads=1, out=path, resume=True)
    assert np.array_equal(resumed["labels"], whole["labels"])
    assert resumed["attractors"] == whole["attractors"]
    assert all("lyapunov_exponents" in a for a in resumed["attractors"])
    with h5py.File(ref, "r") as a, h5py.File(path, "r") as b:
        assert np.array_equal(a["basin/labels"][()], b["basin/labels"][()])
        for k in a["attractors"]:
            assert np.array_equal(a["attractors"][k][()], b["attractors"][k][()], equal_nan=a["attractors"][k].dtype.kind == "f"), k


def test_refusals_name_the_argument_and_leave_the_file(tmp_path):
    path = str(tmp_path / "run.h5")
    scene = vibro.load_scene(FIG8, set={"run.periods": 50})
    vibro.simulate(scene, out=path)
    before = digest(path)
    cases = [
        (dict(extend=5), "extend needs out=FILE.h5"),
        (dict(resume=True), "resume needs out=FILE.h5"),
        (dict(out=path, resume=True, extend=5), "resume and extend: give one"),
        (dict(out=path, extend=0), "(extend 0): expected 1 ≤ N"),
        (dict(out=path, extend=2.5), "extend 2.5: expected an integer"),
        (dict(out=path, resume="yes"), "resume 'yes': expected True or False"),
        (dict(out=path, resume=True), "nothing to resume: the run finished (status ok; extend=N continues it"),
        (dict(out=str(tmp_path / "none.h5"), extend=5), "no such file"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError) as e:
            vibro.simulate(scene, **kwargs)
        assert message in str(e.value), (kwargs, str(e.value))
    with pytest.raises(ValueError) as e:
        vibro.simulate(scene.with_({"excitation.amplitude": 1.3}), out=path, extend=5)
    assert "different scene (or different set= overrides)" in str(e.value)
    # The store's refusals name Python's arguments, not the command line's options.
    with pytest.raises(ValueError) as e:
        vibro.simulate(scene.with_({"run.periods": 80}), out=path, resume=True)
    assert ('resume it with set={"run.periods": 50}, or continue it for N more periods with extend=N'
            in str(e.value)) and "--" not in str(e.value), str(e.value)
    with pytest.raises(ValueError) as e:
        vibro.basin(scene, grid=(4, 4), resume=True)
    assert "resume needs out=FILE.h5 (the study to continue)" in str(e.value)
    assert digest(path) == before
    assert not (tmp_path / "none.h5").exists()


def test_resumed_and_extended_loads_are_those_of_the_whole_run(tmp_path):
    # docs/loads.md §5: the file keeps every period's loads (/loads), so a run stopped by its
    # progress callback and resumed, and a run extended, report the loads and loads_window of the
    # run that went through, every value to the bit.
    total = 60000
    scene = vibro.load_scene(FIG8, set={"run.periods": total, "run.samples_per_period": 4})
    whole = vibro.simulate(scene).summary
    path = str(tmp_path / "run.h5")
    with pytest.raises(Stop):
        vibro.simulate(scene, out=path, progress=stop_after(1000))
    with h5py.File(path, "r") as f:
        stopped = int(f["checkpoint"].attrs["period"])
    assert 0 < stopped < total
    resumed = vibro.simulate(scene, out=path, resume=True).summary
    assert resumed["loads_window"] == whole["loads_window"] and resumed["loads_window"]["whole_run"] is True
    assert resumed["loads"] == whole["loads"]
    # Extended: 2 contacts, 2000 periods + 3000, against 5000 from the start.
    pair = os.path.join(SCENES, "contacts_impact_pair.toml")
    ext = str(tmp_path / "pair.h5")
    vibro.simulate(vibro.load_scene(pair, set={"run.periods": 2000}), out=ext)
    extended = vibro.simulate(vibro.load_scene(pair, set={"run.periods": 2000}), out=ext, extend=3000).summary
    ref = vibro.simulate(vibro.load_scene(pair, set={"run.periods": 5000})).summary
    assert extended["loads_window"] == ref["loads_window"] and ref["loads_window"]["first_period"] == 500
    assert extended["loads"] == ref["loads"] and len(ref["loads"]) == 2
