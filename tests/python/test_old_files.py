"""Files written before the typed layout (attribute tables, shape-(1,) float scalars, no
provenance, a root /attractor in studies) stay readable by `vibro info` and `vibro plot`. The old
layout is made here from a new file with h5py, as the previous writer laid it out."""
import os
import subprocess

import h5py
import numpy as np

from conftest import CLI, SCENES


def run(*args):
    return subprocess.run([CLI, *args], capture_output=True, text=True, timeout=600)


def to_old_layout(path):
    with h5py.File(path, "r+") as f:
        for k in ("git_commit", "command", "command_line", "options", "scene_resolved"):
            del f.attrs[k]
        if "attractors" in f:  # columns as attributes, strings comma-joined, nulls −1
            t = {k: f["attractors"][k] for k in f["attractors"]}
            cols = {k: (",".join(v.asstr()[()]) if h5py.check_string_dtype(v.dtype) else v[()]) for k, v in t.items()}
            del f["attractors"]
            g = f.create_group("attractors")
            for k, v in cols.items():
                if k in ("multiplier_offset",):
                    continue
                if isinstance(v, str):
                    g.attrs[k] = v
                else:
                    g.attrs[k] = np.nan_to_num(np.asarray(v, dtype=float), nan=-1.0)
            f.create_group("attractor").attrs["kind"] = "not-periodic"
        if "orbit" in f:
            a = dict(f["orbit"].attrs)
            mu = a.pop("multipliers").reshape(-1, 2)
            for k in list(f["orbit"].attrs):
                del f["orbit"].attrs[k]
            o = f["orbit"].attrs
            o["multipliers_re"], o["multipliers_im"] = mu[:, 0], mu[:, 1]
            for k in ("stable", "period", "newton_iterations", "residual", "section_time"):
                o[k] = np.array([float(a[k])])
            o["X"], o["V"] = a["X"], a["V"]
        for k in ("form", "mode_shapes", "dof_labels"):
            if k in f["model"].attrs:
                del f["model"].attrs[k]


def test_old_basin_and_orbit_files_still_read_and_plot(tmp_path):
    fig05 = os.path.join(SCENES, "fig05_coexistence.toml")
    chain2 = os.path.join(SCENES, "chain2.toml")
    basin, orbit = str(tmp_path / "basin.h5"), str(tmp_path / "orbit.h5")
    assert run("basin", fig05, "--grid", "6,6", "--set", "run.periods=60", "--out", basin).returncode == 0
    assert run("orbit", chain2, "--out", orbit).returncode == 0
    to_old_layout(basin)
    to_old_layout(orbit)
    for path, picture in ((basin, "basin"), (orbit, "multipliers")):
        p = run("info", path)
        assert p.returncode == 0 and "status       ok" in p.stdout, p.stderr
        prefix = str(tmp_path / os.path.basename(path)[:-3])
        p = run("plot", path, "--out", prefix)
        assert p.returncode == 0, p.stderr
        assert os.path.getsize(f"{prefix}_{picture}.png") > 0


def test_not_a_vibro_file_is_refused_clearly(tmp_path):
    path = str(tmp_path / "other.h5")
    with h5py.File(path, "w") as f:
        f["x"] = np.arange(3)
    for cmd in ("info", "plot"):
        p = run(cmd, path)
        assert p.returncode == 2 and "not a vibro output file" in p.stderr, (cmd, p.stderr)
