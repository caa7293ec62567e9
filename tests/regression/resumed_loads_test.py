#!/usr/bin/python3
"""The loads of a resumed or extended run are those of the whole run (docs/loads.md §5), through
the real binary: a run interrupted (SIGINT once its file holds a checkpoint past a given period)
and resumed (or killed and resumed), and a run extended (finished, or interrupted), report in JSON the same `loads` and
`loads_window`, to the bit, as the run that went through the total length from the start; with one
contact (Fig. 8, short runs of one period per row and long ones whose rows are merged into buckets)
and with two (the impact pair). The per-period rows the file keeps (/loads) are checked against
the file's own events (impacts counted, impulses summed per period and contact), and the JSON means
against those rows. A file written before /loads existed (its /loads removed) is resumed and
extended with `whole_run` false and a window that starts at its checkpoint.
"""
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

vibro, scenes = sys.argv[1], sys.argv[2]
fig8 = os.path.join(scenes, "fig08_preload.toml")
pair = os.path.join(scenes, "contacts_impact_pair.toml")


def run(*args, timeout=900):
    return subprocess.run([vibro, *args], capture_output=True, text=True, timeout=timeout)


def summary(label, *args):
    p = run(*args, "--json")
    check(f"{label}: exit 0", p.returncode == 0, p.stderr[-2000:])
    return json.loads(p.stdout) if p.returncode == 0 else {}


def same_loads(label, got, want):
    """`loads` and `loads_window` equal, every value to the bit (JSON numbers are printed in full)."""
    check(f"{label}: loads_window as the uninterrupted run's", got.get("loads_window") == want.get("loads_window"),
          (got.get("loads_window"), want.get("loads_window")))
    a, b = got.get("loads", []), want.get("loads", [])
    check(f"{label}: loads of {len(b)} contacts", len(a) == len(b) and len(b) > 0, (len(a), len(b)))
    for x, y in zip(a, b):
        for key in sorted(set(x) | set(y)):
            check(f"{label}: contact {y.get('contact')} {key} identical", x.get(key) == y.get(key),
                  (x.get(key), y.get(key)))


def interrupt(args, path, past_period, sig=signal.SIGINT):
    """Runs vibro with `args`, sends `sig` once the file is running with a checkpoint past
    `past_period` (a flush of this invocation reached the disk) and returns the exit code and stderr."""
    proc = subprocess.Popen([vibro, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 600
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.1)
        try:
            with h5py.File(path, "r") as f:
                if f.attrs["status"] == "running" and f["checkpoint"].attrs["period"] > past_period:
                    break
        except Exception:  # noqa: BLE001 (not created yet, or a flush in progress)
            pass
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=600)
    return proc.returncode, err


def checkpoint_period(path):
    with h5py.File(path, "r") as f:
        return int(f["checkpoint"].attrs["period"]), str(f.attrs["status"])


def strip_loads(path):
    """What a file written before /loads looks like: no /loads, no checkpoint loads_periods."""
    with h5py.File(path, "r+") as f:
        if "loads" in f:
            del f["loads"]
        if "loads_periods" in f["checkpoint"].attrs:
            del f["checkpoint"].attrs["loads_periods"]


def rows_against_events(label, path, contacts):
    """/loads holds one row per period from period 0; its impacts and impulses are those of /events."""
    with h5py.File(path, "r") as f:
        check(f"{label}: /loads present", "loads" in f, list(f))
        if "loads" not in f:
            return
        g = f["loads"]
        periods = int(f.attrs["periods"])
        check(f"{label}: /loads from period 0", int(g.attrs["first_period"]) == 0, dict(g.attrs))
        check(f"{label}: /loads one row per period, one column per contact",
              g["impacts"].shape == (periods, contacts) and g["partial"].shape == (periods, contacts),
              g["impacts"].shape)
        check(f"{label}: checkpoint loads_periods", int(f["checkpoint"].attrs["loads_periods"]) == periods,
              dict(f["checkpoint"].attrs).get("loads_periods"))
        kind = f["events/kind"][()]
        per = f["events/period"][()]
        con = f["events/contact"][()]
        imp = f["events/impulse"][()]
        kinds = h5py.check_enum_dtype(f["events/kind"].dtype)
        counts = np.zeros((periods, contacts))
        impulses = np.zeros((periods, contacts))
        is_impact = kind == kinds["impact"]
        np.add.at(counts, (per[is_impact], con[is_impact]), 1)
        carries = is_impact | (kind == kinds["accumulation"])
        np.add.at(impulses, (per[carries], con[carries]), imp[carries])
        check(f"{label}: /loads/impacts = impacts of /events per period and contact",
              np.array_equal(g["impacts"][()], counts), np.abs(g["impacts"][()] - counts).max())
        check(f"{label}: /loads/impulse = impulses of /events per period and contact",
              np.allclose(g["impulse"][()], impulses, rtol=1e-12, atol=1e-12),
              np.abs(g["impulse"][()] - impulses).max())


def means_over_rows(label, path, js):
    """The JSON means are those of the stored rows over the JSON's window (to rounding)."""
    w = js.get("loads_window", {})
    a, b = w["first_period"], w["first_period"] + w["periods"]
    with h5py.File(path, "r") as f:
        check(f"{label}: /loads present for the means", "loads" in f, list(f))
        if "loads" not in f or "first_period" not in w:
            return
        g = f["loads"]
        first = int(g.attrs["first_period"])
        impacts = g["impacts"][a - first:b - first].sum(axis=0)
        impulse = g["impulse"][a - first:b - first].sum(axis=0)
        work = g["work"][a - first:b - first].sum(axis=0)
        period = 2 * np.pi / float(f["model"].attrs["frequency"]) if "frequency" in f["model"].attrs else None
    n = b - a
    for j, c in enumerate(js["loads"]):
        check(f"{label}: contact {j} impacts per period over periods {a}..{b}",
              abs(c["impacts_per_period"] - impacts[j] / n) <= 1e-12 * max(1, abs(c["impacts_per_period"])),
              (c["impacts_per_period"], impacts[j] / n))
        check(f"{label}: contact {j} impulse per period over periods {a}..{b}",
              abs(c["impulse_per_period"] - impulse[j] / n) <= 1e-11 * max(1, abs(c["impulse_per_period"])),
              (c["impulse_per_period"], impulse[j] / n))
        if period:
            check(f"{label}: contact {j} work rate over periods {a}..{b}",
                  abs(c["work_rate"] - work[j] / (n * period)) <= 1e-11 * max(1, abs(c["work_rate"])),
                  (c["work_rate"], work[j] / (n * period)))


with tempfile.TemporaryDirectory() as d:
    # --- One contact, one period per row: extended twice, and interrupted then extended -----------
    ref = summary("fig8 8000", "simulate", fig8, "--set", "run.periods=8000", "--out", os.path.join(d, "r8k.h5"))
    check("fig8 8000: the whole run's window", ref.get("loads_window", {}).get("first_period") == 800 and
          ref["loads_window"].get("whole_run") is True, ref.get("loads_window"))
    rows_against_events("fig8 8000", os.path.join(d, "r8k.h5"), 1)
    means_over_rows("fig8 8000", os.path.join(d, "r8k.h5"), ref)
    path = os.path.join(d, "e8k.h5")
    summary("fig8 3000", "simulate", fig8, "--set", "run.periods=3000", "--out", path)
    shutil.copy(path, os.path.join(d, "old3k.h5"))
    got = summary("fig8 3000 +2000", "simulate", fig8, "--out", path, "--extend", "2000")
    ref5 = summary("fig8 5000", "simulate", fig8, "--set", "run.periods=5000")
    same_loads("fig8 3000 +2000", got, ref5)
    got = summary("fig8 3000 +2000 +3000", "simulate", fig8, "--out", path, "--extend", "3000")
    same_loads("fig8 3000 +2000 +3000", got, ref)
    # --blocks changes the summary, not what is stored.
    got = summary("fig8 extended, --blocks 7", "simulate", fig8, "--set", "run.periods=8000", "--out",
                  os.path.join(d, "r8k_b7.h5"), "--blocks", "7")
    path = os.path.join(d, "e8k_b7.h5")
    summary("fig8 3000 (b7)", "simulate", fig8, "--set", "run.periods=3000", "--out", path)
    same_loads("fig8 3000 +5000 --blocks 7",
               summary("fig8 +5000 b7", "simulate", fig8, "--out", path, "--extend", "5000", "--blocks", "7"), got)

    # --- One contact, rows merged into buckets (270 000 periods analysed > 2^16) ------------------
    # Runs long enough (seconds, not the store's first flush at 1 s) to be interrupted on any machine.
    total = 300000
    long_ref_path = os.path.join(d, "r_long.h5")
    long_ref = summary(f"fig8 {total}", "simulate", fig8, "--set", f"run.periods={total}", "--out", long_ref_path)
    means_over_rows(f"fig8 {total}", long_ref_path, long_ref)
    path = os.path.join(d, "i_long.h5")
    code, err = interrupt(["simulate", fig8, "--set", f"run.periods={total}", "--out", path], path, 2000)
    check(f"fig8 {total} interrupted: exit 130", code == 130, (code, err[-2000:]))
    stopped, status = checkpoint_period(path)
    check(f"fig8 {total} interrupted inside the run", status == "interrupted" and 2000 < stopped < total,
          (status, stopped))
    old = os.path.join(d, "old_i_long.h5")
    shutil.copy(path, old)
    got = summary(f"fig8 {total} resumed", "simulate", fig8, "--set", f"run.periods={total}", "--out", path, "--resume")
    same_loads(f"fig8 {total} resumed at period {stopped}", got, long_ref)
    # Interrupted, then extended past its length.
    path = os.path.join(d, "i100k.h5")
    code, err = interrupt(["simulate", fig8, "--set", "run.periods=100000", "--out", path], path, 1000)
    check("fig8 100000 interrupted: exit 130", code == 130, (code, err[-2000:]))
    stopped, status = checkpoint_period(path)
    check("fig8 100000 interrupted inside the run", status == "interrupted" and 1000 < stopped < 100000,
          (status, stopped))
    got = summary("fig8 100000 interrupted +200000", "simulate", fig8, "--out", path, "--extend", "200000")
    same_loads(f"fig8 interrupted at {stopped} of 100000, extended by 200000", got, long_ref)

    # --- Two contacts (the impact pair) --------------------------------------------------------------
    pair_total = 60000
    pair_ref_path = os.path.join(d, "pair_ref.h5")
    pair_ref = summary(f"pair {pair_total}", "simulate", pair, "--set", f"run.periods={pair_total}", "--out", pair_ref_path)
    rows_against_events(f"pair {pair_total}", pair_ref_path, 2)
    means_over_rows(f"pair {pair_total}", pair_ref_path, pair_ref)
    path = os.path.join(d, "pair.h5")
    code, err = interrupt(["simulate", pair, "--set", f"run.periods={pair_total}", "--out", path], path, 300)
    check("pair interrupted: exit 130", code == 130, (code, err[-2000:]))
    stopped, status = checkpoint_period(path)
    check("pair interrupted inside the run", status == "interrupted" and 300 < stopped < pair_total, (status, stopped))
    got = summary("pair resumed", "simulate", pair, "--set", f"run.periods={pair_total}", "--out", path, "--resume")
    same_loads(f"pair resumed at period {stopped}", got, pair_ref)
    # Killed (the file as its last flush left it, status "running"), then resumed.
    path = os.path.join(d, "pair_killed.h5")
    code, err = interrupt(["simulate", pair, "--set", f"run.periods={pair_total}", "--out", path], path, 300,
                          signal.SIGKILL)
    check("pair killed: exit -9", code == -signal.SIGKILL, (code, err[-2000:]))
    stopped, status = checkpoint_period(path)
    check("pair killed inside the run", status == "running" and 300 < stopped < pair_total, (status, stopped))
    got = summary("pair killed, resumed", "simulate", pair, "--set", f"run.periods={pair_total}", "--out", path,
                  "--resume")
    same_loads(f"pair killed, resumed at period {stopped}", got, pair_ref)
    path = os.path.join(d, "pair_ext.h5")
    summary("pair 2000", "simulate", pair, "--set", "run.periods=2000", "--out", path)
    got = summary("pair 2000 +3000", "simulate", pair, "--out", path, "--extend", "3000")
    same_loads("pair 2000 +3000", got, summary("pair 5000", "simulate", pair, "--set", "run.periods=5000"))

    # --- Files written before /loads -----------------------------------------------------------------
    # A finished run of 3000 periods extended by 5000: periods 0..3000 are not known, so the window
    # is 3000..8000 (not 800..8000), and the JSON says so.
    path = os.path.join(d, "old3k.h5")
    strip_loads(path)
    got = summary("old file +5000", "simulate", fig8, "--out", path, "--extend", "5000")
    w = got.get("loads_window", {})
    check("old file extended: whole_run false, known from its checkpoint",
          w.get("whole_run") is False and w.get("known_from") == 3000, w)
    check("old file extended: the window starts at the checkpoint",
          w.get("first_period") == 3000 and w.get("periods") == 5000, w)
    check("old file extended: coverage says which periods", "3000..8000" in w.get("coverage", "") and
          "800" in w.get("coverage", ""), w.get("coverage"))
    means_over_rows("old file extended", path, got)
    p = run("simulate", fig8, "--set", "run.periods=8000", "--out", path, "--extend", "10")
    check("old file extended again: text output says not the whole run",
          p.returncode == 0 and "loads        not the whole run: the periods before 3000 are not known" in p.stdout,
          p.stdout[-3000:] + p.stderr[-2000:])
    # An interrupted run resumed: the window starts at its checkpoint (past the first tenth).
    stopped, _ = checkpoint_period(old)
    strip_loads(old)
    got = summary("old interrupted file resumed", "simulate", fig8, "--set", f"run.periods={total}", "--out", old,
                  "--resume")
    w = got.get("loads_window", {})
    check("old file resumed: whole_run", w.get("whole_run") is (stopped <= total // 10), (w, stopped))
    check("old file resumed: the window starts at max(checkpoint, first tenth)",
          w.get("first_period", -1) >= max(stopped, total // 10) and
          w.get("first_period", 0) + w.get("periods", 0) == total, (w, stopped))
    if stopped > total // 10:
        check("old file resumed: known_from is the checkpoint", w.get("known_from") == stopped, (w, stopped))
    with h5py.File(old, "r") as f:
        check("old file resumed: /loads begins at the checkpoint", "loads" in f and
              int(f["loads"].attrs["first_period"]) == stopped and f["loads/impacts"].shape[0] == total - stopped,
              dict(f["loads"].attrs) if "loads" in f else list(f))

finish()
