"""The arrays of vibro.simulate are the rows the same run writes to HDF5 (read with h5py)."""
import os
import re
import subprocess

import h5py
import numpy as np

import vibro
from conftest import SCENES


def test_arrays_equal_hdf5(tmp_path):
    out = tmp_path / "run.h5"
    scene = vibro.load_scene(os.path.join(SCENES, "chain2.toml"),
                             set={"run.periods": 30, "run.samples_per_period": 16})
    run = vibro.simulate(scene, out=out)
    assert len(run.events) > 10 and len(run.samples) >= 30 * 16
    with h5py.File(out, "r") as f:
        for k in ("t", "x_B", "v_before", "v_after"):
            np.testing.assert_array_equal(run.events[k], f["events"][k][:])
        np.testing.assert_array_equal(run.events["kind"], f["events/kind"][:].astype(np.int8))
        for k in ("t", "X", "V", "x_B", "mode"):
            np.testing.assert_array_equal(run.samples[k], f["samples"][k][:])
        for k in ("t", "X", "V"):
            np.testing.assert_array_equal(run.section[k], f["section"][k][:])
        assert f.attrs["status"] in ("ok", b"ok")
    # The event kinds are the HDF5 enum's values.
    with h5py.File(out, "r") as f:
        enum = h5py.check_enum_dtype(f["events/kind"].dtype)
    assert {v: k for k, v in enum.items()} == vibro.EVENT_KINDS


def test_samples_are_the_model():
    """Independent truth (paper's scaling, MODEL §1.3): the contact point moves as x_B = Σ X_i over
    the modes that move B (T_B,i ≠ 0), and sits on the stop x0 while sticking."""
    scene = vibro.load_scene(os.path.join(SCENES, "chain3.toml"), set={"run.periods": 10})
    run = vibro.simulate(scene)
    moves_b = (np.asarray(vibro.model(scene)["contact"]) != 0).astype(float)
    np.testing.assert_allclose(run.samples["X"] @ moves_b, run.samples["x_B"], rtol=0, atol=1e-12)
    stop = float(re.search(r"position\s*=\s*([-+0-9.eE]+)", scene.text).group(1))
    on = run.samples["mode"] == 1
    assert on.any()
    np.testing.assert_allclose(run.samples["x_B"][on], stop, atol=1e-9)


def test_a_programs_own_exit_status_is_kept_after_writing_a_file(tmp_path):
    # vibro reports HDF5's own exit(-1) during a file's writes as out of memory (exit 3); a
    # program that exits with -1 itself, after vibro wrote its file, keeps its status 255.
    import sys
    code = ("import sys, vibro\n"
            f"vibro.simulate(vibro.load_scene({os.path.join(SCENES, 'default.toml')!r}, set={{'run.periods': 5}}), "
            f"out={str(tmp_path / 'x.h5')!r})\n"
            "sys.exit(-1)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    assert r.returncode == 255, (r.returncode, r.stderr)
    assert "out of memory" not in r.stderr
