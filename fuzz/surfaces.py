#!/usr/bin/python3
"""A fuzz campaign over the surfaces that campaign.py does not reach (docs/reliability.md):

- from-branch: continuation branch files given to `continue --from FILE --point K`, damaged by
  bit flips and by targeted edits (empty or short state tables, a state below the stop, a branch
  of another scene, strings where numbers belong, attributes out of range, datasets declaring
  billions of elements);
- validate-input: branch CSVs given to `vibro validate`, with altered states, non-finite values,
  duplicate columns, a UTF-8 BOM, garbage and endless files;
- score-input: event CSVs given to `vibro score`, with events shifted, dropped or added, times
  out of range or out of order, duplicate columns, a BOM, and extreme `--window` values;
- python-api: every Python function called with corner arguments, and Ctrl-C during the long ones;
- prove-branch: `prove --branch` with the damaged branch files of from-branch, a tiny --time-limit
  or a stop signal at a random moment, its certificates given to the proof checker;
- two-writers: a second process on the output file of a running one (the same --out, with and
  without --force, and --resume), and two --resume of one interrupted file at once;
- full-disk: runs whose output lives on a 3 MiB tmpfs (when this process may mount one);
- contacts: `partition`, `check`, `sweep` and `attractors` on the scenes with several contacts,
  with random (sometimes invalid) options, a random --time-limit and stop signals;
- sequence-column: branch CSVs of a two-contact branch given to `vibro validate` with the
  `sequence` column mutated (garbage, unknown contact names, empty, very long, control
  characters, numbers) and event CSVs given to `vibro score` with a mutated `contact` column;
- extend-fsize: `simulate --extend N` of a stored run under a file-size limit (ulimit -f, the full
  disk of a process): exit 3 naming the limit, the file readable.

Each run is judged as campaign.py judges its runs (no crash, no hang, the allowed exit codes,
exit 2 located and changing nothing, `ok` files within the physics), and against the promise of
its surface:

- an input that is invalid by construction (a non-finite time, a state below the stop, a branch
  of another scene...) is refused with exit 2; an input that is valid but wrong (a shifted event,
  an altered state) is never reported as agreeing (exit 4, or that row not `confirmed`);
- an unaltered input is accepted (exit 0);
- Python raises ValueError or TypeError for a bad argument (never MemoryError, IndexError,
  SystemError or a crash), and KeyboardInterrupt within LIVENESS s of its own time (campaign.py's
  StopClock: CPU time and time asleep, not the time a loaded machine keeps it waiting) of Ctrl-C;
- a second writer is refused with exit 2 naming the process that holds the file, and the first
  run ends as it would alone, its file readable;
- a full disk ends a run with exit 3 ("no space") or 130, never 1 or a crash, its file readable.

usage: surfaces.py VIBRO SCENES_DIR SCRIPTS_DIR PYTHONPATH [--runs N] [--seed S] [--minutes M]
                   [--report FILE.json] [--only CATEGORY]
Exits 1 when there are findings; the report lists each with its command line.
"""
import argparse
import csv
import hashlib
import io
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

import h5py
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from campaign import (Campaign, StopClock, children_cpu, default_stop_signals, wait_stopping,  # noqa: E402
                      write_report, HANG, HANG_WALL, LIVENESS)

CATEGORIES = ["from-branch", "validate-input", "score-input", "python-api", "two-writers", "full-disk", "prove-branch",
              "contacts", "sequence-column", "extend-fsize", "compliant", "harmonics", "curve", "prove-bifurcation",
              "checker"]

# The symmetric two-sided oscillator of docs/prove.md (its pitchfork at a = 3.2860503573579958).
PITCHFORK = """title = "1-DOF two-sided clearance: stops at -1 and +1, r = 0.6, omega = 2"
[structure]
mass = [[1.0]]
stiffness = [[1.0]]
forcing_dof = 0
[[contact]]
dof = 0
side = "below"
position = -1.0
restitution = 0.6
[[contact]]
dof = 0
side = "above"
position = 1.0
restitution = 0.6
[excitation]
amplitude = 3.0
frequency = 2.0
[initial]
displacement = [0.0]
velocity = [0.0]
[run]
periods = 20
"""


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    return rows[0], rows[1:]


def write_csv(path, header, rows, bom=False):
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    with open(path, "w", newline="", encoding="utf-8-sig" if bom else "utf-8") as f:
        f.write(buf.getvalue())


class Surfaces(Campaign):
    def __init__(self, vibro, scenes, scripts, pythonpath, seed, deadline, work):
        super().__init__(vibro, scenes, seed, deadline, work)
        self.scripts, self.pythonpath = scripts, pythonpath
        self.default = os.path.join(scenes, "fig08_preload.toml")
        self.chain2 = os.path.join(scenes, "chain2.toml")
        self.fig5 = os.path.join(scenes, "fig05_coexistence.toml")
        self.can_mount = None
        self.certificates = []  # certificate files for the checker's runs
        self.base_codes = {}    # certificate → the checker's exit code on it, unmutated

    # ---- seeds: files made by vibro itself ----
    def make(self, argv, out):
        p = subprocess.run([self.vibro, *argv], capture_output=True, text=True, timeout=300)
        if p.returncode != 0 or not os.path.exists(out):
            raise RuntimeError(f"seed {' '.join(argv)} failed ({p.returncode}): {p.stderr}")
        return out

    def seeds_(self):
        d = os.path.join(self.work, "seeds")
        os.mkdir(d)
        s = {}
        s["branch"] = self.make(["continue", self.default, "--param", "excitation.amplitude", "--to", "1.25",
                                 "--max-points", "8", "--out", os.path.join(d, "b.h5")], os.path.join(d, "b.h5"))
        s["branch2"] = self.make(["continue", self.chain2, "--param", "excitation.frequency", "--to", "0.75",
                                  "--max-points", "6", "--out", os.path.join(d, "b2.h5")], os.path.join(d, "b2.h5"))
        # An impacting branch for prove --branch: three points and the segments between them.
        s["branch_impact"] = self.make(["continue", self.fig5, "--kind", "impact", "--param", "excitation.amplitude",
                                        "--to", "1.3", "--step", "0.002", "--max-points", "3", "--out",
                                        os.path.join(d, "b3.h5")], os.path.join(d, "b3.h5"))
        csv_path = os.path.join(d, "b.csv")
        subprocess.run(["/usr/bin/python3", os.path.join(self.scripts, "branch_to_csv.py"), s["branch"], csv_path],
                       check=True, capture_output=True, timeout=60)
        s["branch_csv"] = csv_path
        run = self.make(["simulate", self.default, "--set", "run.periods=6", "--out", os.path.join(d, "th.h5")],
                        os.path.join(d, "th.h5"))
        ev = os.path.join(d, "th.csv")
        subprocess.run(["/usr/bin/python3", os.path.join(self.scripts, "events_to_csv.py"), run, ev],
                       check=True, capture_output=True, timeout=60)
        s["events_csv"] = ev
        # Two contacts: a branch with a sequence column, events with a contact column, a run to extend.
        two = os.path.join(self.scenes, "contacts_two_sided_1dof.toml")
        s["branch_seq"] = self.make(["continue", two, "--param", "excitation.amplitude", "--to", "1.2",
                                     "--max-points", "5", "--out", os.path.join(d, "bs.h5")], os.path.join(d, "bs.h5"))
        seq_csv = os.path.join(d, "bs.csv")
        subprocess.run(["/usr/bin/python3", os.path.join(self.scripts, "branch_to_csv.py"), s["branch_seq"], seq_csv],
                       check=True, capture_output=True, timeout=60)
        s["branch_seq_csv"] = seq_csv
        run2 = self.make(["simulate", two, "--set", "run.periods=6", "--out", os.path.join(d, "th2.h5")],
                         os.path.join(d, "th2.h5"))
        ev2 = os.path.join(d, "th2.csv")
        subprocess.run(["/usr/bin/python3", os.path.join(self.scripts, "events_to_csv.py"), run2, ev2],
                       check=True, capture_output=True, timeout=60)
        s["events_contacts_csv"] = ev2
        self.seed_files = s
        # prove --bifurcation and curve --from: the pitchfork branch of docs/prove.md.
        self.pitchfork = os.path.join(d, "pitchfork.toml")
        with open(self.pitchfork, "w") as f:
            f.write(PITCHFORK)
        bif = os.path.join(d, "bif.h5")
        p = subprocess.run([self.vibro, "continue", self.pitchfork, "--param", "excitation.amplitude", "--to", "3.6",
                            "--out", bif], capture_output=True, text=True, timeout=600)
        m = re.search(r"branch-point at excitation.amplitude = ([0-9.eE+-]+)", p.stdout)
        if p.returncode != 0 or not m:
            raise RuntimeError(f"seed: the pitchfork branch ({p.returncode}): {p.stdout[-300:]} {p.stderr[-300:]}")
        s["branch_bif"] = bif
        self.bif_value = float(m.group(1))

    def seed_certificates(self):
        """Certificates of every kind for the checker's runs: an impacting orbit, a sticking one, a
        pitchfork, a branch's (points and segments)."""
        d = os.path.join(self.work, "seeds")
        jobs = [("orbit", ["prove", self.fig5]), ("sticking", ["prove", self.default]),
                ("pitchfork", ["prove", self.pitchfork, "--bifurcation", self.seed_files["branch_bif"]]),
                ("branch", ["prove", self.fig5, "--branch", self.seed_files["branch_impact"]])]
        for name, argv in jobs:
            out = os.path.join(d, f"cert_{name}.json")
            p = subprocess.run([self.vibro, *argv, "--out", out], capture_output=True, text=True, timeout=900)
            if os.path.exists(out):
                self.certificates.append(out)
            else:
                print(f"seed certificate {name}: exit {p.returncode}, none written: {p.stderr[-300:]}", flush=True)

    # ---- from-branch ----
    def damaged_branch(self, point, seed="branch"):
        """A copy of a seed branch with one damage; returns (path, what, valid) where valid is
        False when the damage makes the file one vibro must refuse, None when it cannot tell."""
        r = self.rng
        src = self.seed_files[seed]
        path = self.fresh(".h5")
        shutil.copy(src, path)
        what = r.choice(["bits", "bits", "empty-rows", "empty-cols", "short-X", "below-stop", "other-scene",
                         "string-values", "period-wrap", "huge-value", "nan-state", "negative-period",
                         "missing-X", "untouched"])
        valid = False
        if what == "bits":
            data = bytearray(open(path, "rb").read())
            for _ in range(r.randint(1, 24)):
                data[r.randrange(len(data))] ^= 1 << r.randrange(8)
            open(path, "wb").write(data)
            valid = None
        elif what == "other-scene":
            shutil.copy(self.seed_files["branch2"], path)
        elif what == "untouched":
            valid = True
        else:
            with h5py.File(path, "r+") as f:
                b = f["branch"]
                n = b["value"].shape[0]

                def replace(name, data):
                    del b[name]
                    b.create_dataset(name, data=data)
                if what == "empty-rows":
                    replace(r.choice(["X", "V"]), np.zeros((0, 1)))
                elif what == "empty-cols":
                    replace(r.choice(["X", "V"]), np.zeros((n, 0)))
                elif what == "short-X":
                    replace("X", b["X"][: max(0, n - 3)])
                elif what == "below-stop":
                    stop = float(f["model"].attrs["stop"])
                    replace("X", np.full((n, 1), stop - r.choice([0.5, 1e-3, 1e3])))
                    replace("V", np.zeros((n, 1)))
                elif what == "string-values":
                    name = r.choice(["X", "V", "value", "section_time"])
                    replace(name, np.array([b"abc"] * n, dtype=object) if name != "X" else np.array([[b"x"]] * n))
                elif what == "period-wrap":
                    b.attrs["period"] = np.uint64(2 ** 32 + 1)
                elif what == "negative-period":
                    b.attrs["period"] = np.int64(r.choice([-1, 0, 2 ** 62]))
                elif what == "huge-value":
                    del b["value"]
                    b.create_dataset("value", shape=(r.choice([2 ** 31, 2 ** 34, 2 ** 40]),), dtype="f8",
                                     chunks=(1024,), compression="gzip")
                elif what == "nan-state":
                    # In the row that --point asks for: --from reads that row alone.
                    X = b["X"][:]
                    X[min(point, n - 1) if point >= 0 else 0, 0] = r.choice([np.nan, np.inf, -np.inf])
                    replace("X", X)
                elif what == "missing-X":
                    del b[r.choice(["X", "V", "value", "section_time"])]
        return path, what, valid

    def gen_from_branch(self):
        r = self.rng
        point = r.choice([0, 1, 5, 7, 8, 1000, -1])
        path, what, valid = self.damaged_branch(point)
        out = self.fresh(".h5")
        argv = ["continue", self.default, "--from", path, "--point", str(point), "--param", "excitation.amplitude",
                "--to", "1.26", "--max-points", "3", "--out", out]
        rc, err = self.run("from-branch", argv, limit=30, watch=[path, self.work], out=out, key=what)
        in_range = 0 <= point < 8
        if rc == 0 and (valid is False or not in_range):
            self.find("accepted a branch file it must refuse", [self.vibro, *argv],
                      f"[from-branch] damage {what}, point {point}: exit 0")
        if rc == 2 and valid is True and in_range:
            self.find("refused a valid branch file", [self.vibro, *argv], f"[from-branch] {err}")

    # ---- prove-branch ----
    def gen_prove_branch(self):
        """prove --branch on a damaged impacting branch: refused with exit 2 when the file is invalid
        by construction (a state below the stop is only where the orbit search starts: proving
        from it is allowed); an untouched file proven whole (exit 0); a tiny --time-limit or a
        stop signal ends it (exit 4 or 130); every certificate file written is read by the checker
        in one line with exit 0, 1 or 2, and exit 0 of prove means the checker confirms it."""
        r = self.rng
        path, what, valid = self.damaged_branch(-1, seed="branch_impact")
        if what == "below-stop":
            valid = None
        out = os.path.join(self.work, f"prove{self.runs}.json")
        argv = ["prove", self.fig5, "--branch", path, "--out", out]
        if r.random() < 0.5:
            argv.append("--json")
        limited = r.random() < 0.25
        if limited:
            argv += ["--time-limit", r.choice(["0.001", "0.02", "0.2"])]
        signals = [(r.uniform(0.02, 1.0), r.choice([signal.SIGINT, signal.SIGTERM]))] if r.random() < 0.25 else []
        rc, err = self.run("prove-branch", argv, signals=signals, limit=120, watch=[path], key=what)
        full = [self.vibro, *argv]
        if rc == 0 and valid is False:
            self.find("prove accepted a branch file it must refuse", full, f"[prove-branch] damage {what}: exit 0")
        if rc == 2 and valid is True:
            self.find("prove refused a valid branch file", full, f"[prove-branch] {err}")
        if valid is True and not limited and not signals and rc != 0:
            self.find("prove did not prove an untouched branch", full, f"[prove-branch] exit {rc}: {err[-300:]}")
        if rc in (0, 4) and "--json" in argv:
            try:
                doc = json.loads(self.last_stdout)
                assert isinstance(doc.get("points"), list)
            except (ValueError, AssertionError, AttributeError):
                self.find("prove --branch --json printed no JSON", full, f"[prove-branch] {self.last_stdout[-300:]}")
        if os.path.exists(out):
            p = subprocess.run(["/usr/bin/python3", os.path.join(self.scripts, "vibro_check_proof.py"), out],
                               capture_output=True, text=True, timeout=600)
            lines = p.stdout.splitlines()
            if p.returncode not in (0, 1, 2) or len(lines) != 1 or "Traceback" in p.stderr:
                self.find("the checker failed on a certificate file", full,
                          f"[prove-branch] checker exit {p.returncode}: {p.stdout[-300:]} {p.stderr[-300:]}")
            elif rc == 0 and p.returncode != 0:
                self.find("a branch proven whole that the checker does not confirm", full, f"[prove-branch] {lines[0]}")
            os.remove(out)
        elif rc == 0:
            self.find("prove --branch --out exit 0 wrote no certificates", full, "[prove-branch]")

    # ---- validate-input ----
    def gen_validate_input(self):
        r = self.rng
        header, rows = read_csv(self.seed_files["branch_csv"])
        rows = [list(x) for x in rows]
        what = r.choice(["alter-velocity", "alter-displacement", "non-finite", "dup-column", "bom", "garbage",
                         "untouched", "devzero", "reorder-columns", "empty-cells", "huge-value", "signal"])
        expect = {"exit": None, "row": None}  # the promise for this input
        bom = False
        if what in ("alter-velocity", "alter-displacement"):
            i = r.randrange(len(rows))
            col = header.index("velocity_1" if what == "alter-velocity" else "displacement_1")
            old = float(rows[i][col])
            rows[i][col] = repr(r.choice([-5.0, -1e3, -1e308, 1e3, old + 0.3, -old - 1]))
            expect["row"] = i  # that row must not be confirmed (or the input refused)
        elif what == "non-finite":
            i, j = r.randrange(len(rows)), r.randrange(len(header))
            if header[j] in ("stable", "period"):
                j = header.index("value")
            rows[i][j] = r.choice(["nan", "inf", "-inf", "1e999"])
            expect["exit"] = 2
        elif what == "dup-column":
            j = r.randrange(len(header))
            header = header + [header[j]]
            rows = [x + [x[j]] for x in rows]
            expect["exit"] = 2
        elif what == "bom":
            bom = True
            expect["exit"] = 0
        elif what == "garbage":
            rows.insert(r.randrange(len(rows) + 1), [r.choice(["x", "", "1,2", "\x00", "1e3e3"])] * len(header))
            expect["exit"] = 2
        elif what == "untouched":
            expect["exit"] = 0
        elif what == "reorder-columns":
            order = list(range(len(header)))
            r.shuffle(order)
            header = [header[k] for k in order]
            rows = [[x[k] for k in order] for x in rows]
            expect["exit"] = 0
        elif what == "empty-cells":
            for name in ("period", "stable", "sticking_fraction"):
                if name in header:
                    for x in rows:
                        x[header.index(name)] = ""
            expect["exit"] = 0
        elif what == "huge-value":
            i = r.randrange(len(rows))
            rows[i][header.index("value")] = r.choice(["1e308", "-1e308", "5e-324", "1e20"])
            expect["row"] = i  # refused (exit 2) or judged, but never confirmed there
        elif what == "signal":
            rows = rows * 2500  # 20 000 rows: a stop request must be honoured within a second
        path = "/dev/zero" if what == "devzero" else self.fresh(".csv")
        if what != "devzero":
            write_csv(path, header, rows, bom)
        argv = ["validate", self.default, path, "--param", "excitation.amplitude", "--json"]
        signals = [(r.uniform(0.3, 2.0), r.choice([signal.SIGINT, signal.SIGTERM]))] if what == "signal" else ()
        rc, err = self.run("validate-input", argv, signals=signals, limit=60 if what != "devzero" else 20,
                           watch=[self.work], key=what)
        out = self.last_stdout
        full = [self.vibro, *argv]
        if what == "devzero" and rc != 2:
            self.find("validate read /dev/zero", full, f"[validate-input] exit {rc}")
        if expect["exit"] == 2 and rc not in (2,):
            self.find("validate accepted invalid input", full, f"[validate-input] {what}: exit {rc}")
        if expect["exit"] == 0 and rc not in (0, 4):
            self.find("validate refused valid input", full, f"[validate-input] {what}: exit {rc} {err}")
        if expect["exit"] == 0 and rc == 4:
            self.find("validate disagrees with vibro's own branch", full, f"[validate-input] {what}: {out[-600:]}")
        if expect["row"] is not None and rc in (0, 4):
            try:
                pts = json.loads(out)["points"]
                if pts[expect["row"]]["verdict"] == "confirmed":
                    self.find("validate confirmed an altered state", full,
                              f"[validate-input] row {expect['row']}: {pts[expect['row']]}")
            except (ValueError, KeyError, IndexError) as e:
                self.find("validate printed no usable JSON", full, f"[validate-input] {e}: {out[-300:]}")

    # ---- score-input ----
    def gen_score_input(self):
        r = self.rng
        header, rows = read_csv(self.seed_files["events_csv"])
        rows = [list(x) for x in rows]
        it = header.index("t")
        period = 2 * math.pi / 2.8  # the scene's forcing period (fig08_preload: ω = 2.8)
        what = r.choice(["untouched", "shift", "drop", "drop-tail", "add", "time-huge", "time-nan", "decreasing",
                         "dup-column", "bom", "window-inf", "window-nan", "window-neg", "garbage", "devzero"])
        expect = None
        window = "0.05"
        bom = False
        if what == "untouched":
            expect = 0
        elif what == "shift":
            i = r.randrange(len(rows))
            rows[i][it] = repr(float(rows[i][it]) + r.choice([1e-3, 1e-2, 0.02]) * period)
            times = [float(x[it]) for x in rows]
            # Out of order after the shift: refused (exit 2); in order: a divergence (exit 4). Equal
            # times are in order (an accumulation and its stick share one).
            expect = 4 if all(a <= b for a, b in zip(times, times[1:])) else 2
        elif what == "drop":
            i = r.randrange(len(rows))
            ik = header.index("kind")
            # The last impact before an accumulation is the start of vibro's predicted tail: a
            # simulator that predicts the accumulation one impact earlier lacks it legitimately, and
            # score excuses it (docs/validation.md: vibro's impacts inside the other simulator's own
            # accumulation interval are counted `in acc.`). Any other row is
            # a divergence.
            tail = rows[i][ik] == "impact" and i + 1 < len(rows) and rows[i + 1][ik] == "accumulation"
            del rows[i]
            expect = None if tail else 4
        elif what == "drop-tail":
            rows = rows[: r.randrange(1, len(rows))]
            expect = 4
        elif what == "add":
            i = r.randrange(len(rows) - 1)
            t = 0.5 * (float(rows[i][it]) + float(rows[i + 1][it]))
            new = list(rows[i])
            new[it] = repr(t)
            new[header.index("kind")] = "grazing"
            rows.insert(i + 1, new)
            expect = 4
        elif what in ("time-huge", "time-nan"):
            i = r.randrange(len(rows))
            rows[i][it] = r.choice(["1e308", "1e9", "-1e308"]) if what == "time-huge" else r.choice(["nan", "inf"])
            expect = 2
        elif what == "decreasing":
            i = r.randrange(1, len(rows))
            rows[i - 1], rows[i] = rows[i], rows[i - 1]
            if rows[i - 1][it] != rows[i][it]:
                expect = 2
        elif what == "dup-column":
            header = header + [header[it]]
            rows = [x + [x[it]] for x in rows]
            expect = 2
        elif what == "bom":
            bom = True
            expect = 0
        elif what.startswith("window"):
            window = {"window-inf": "inf", "window-nan": "nan", "window-neg": "-0.1"}[what]
            expect = 2
        elif what == "garbage":
            rows.insert(r.randrange(len(rows) + 1), [r.choice(["x", "", "1e3e3", "\x00"])] * len(header))
            expect = 2
        path = "/dev/zero" if what == "devzero" else self.fresh(".csv")
        if what == "devzero":
            expect = 2
        else:
            write_csv(path, header, rows, bom)
        argv = ["score", self.default, path, "--set", "run.periods=6", "--window", window, "--json"]
        rc, err = self.run("score-input", argv, limit=30, watch=[self.work], key=what)
        full = [self.vibro, *argv]
        if expect is not None and rc != expect:
            self.find(f"score exit {rc} where {expect} is promised", full,
                      f"[score-input] {what}: {err[-300:]} {self.last_stdout[-300:]}")

    # ---- python-api ----
    PY_CASES = [
        ("basin", "vibro.basin(S, grid=(46341, 46341))"),
        ("basin", "vibro.basin(S, grid=(4, 4), threads=-1)"),
        ("basin", "vibro.basin(S, grid=(4, 4), x='X1099511627776')"),
        ("basin", "vibro.basin(S, grid=(0, 4))"),
        ("basin", "vibro.basin(S, grid=(4, 4), x_range=(float('nan'), 1))"),
        ("continue", "vibro.continue_(S, 'excitation.amplitude', float('nan'))"),
        ("continue", "vibro.continue_(S, 'excitation.amplitude', float('inf'))"),
        ("continue", "vibro.continue_(S, 'excitation.amplitude', 1.25, step=float('nan'))"),
        ("continue", "vibro.continue_(S, 'excitation.amplitude', 1.25, max_points=0)"),
        ("continue", "vibro.continue_(S, 'excitation.amplitude', 1.25, max_points=-5)"),
        ("attractors", "vibro.attractors(S, samples=2**31)"),
        ("attractors", "vibro.attractors(S, samples=-1)"),
        ("sweep", "vibro.sweep(S, 'excitation.frequency', 2.0, 3.0, steps=10**9)"),
        ("sweep", "vibro.sweep(S, 'excitation.frequency', 2.0, float('nan'))"),
        ("partition", "vibro.partition(S, ['excitation.amplitude', 'excitation.frequency'], (1.0, 1.2), (2.5, 3.0),"
                      " [0.3], steps1=10**9)"),
        ("load", "vibro.load_scene(SCENE + '\\x00junk')"),
        ("load", "vibro.load_scene(SCENE, set=['excitation.amplitude=nan'])"),
        ("simulate", "vibro.simulate(S.with_(['run.periods=3']))"),
        ("orbit", "vibro.orbit(S, period=-1)"),
        ("orbit", "vibro.orbit(S, guess=(float('nan'), 0.0))"),
        ("score", "vibro.score(S, np.zeros(3))"),
        ("score", "vibro.score(S, 42)"),
        ("validate", "vibro.validate(S, {'value': [1.2]}, 'excitation.amplitude')"),
        ("read", "vibro.read('/dev/zero')"),
        ("info", "vibro.info(SCENE)"),
    ]
    PY_LONG = [
        ("check", "vibro.check(vibro.load_scene(CHAIN3, set=['run.periods=100000000']))"),
        ("orbit", "vibro.orbit(vibro.load_scene(CHAIN3), period=3, transient=100000000)"),
        ("simulate", "vibro.simulate(S.with_(['run.periods=100000000']))"),
        ("basin", "vibro.basin(vibro.load_scene(FIG5), grid=(300, 300), threads=1)"),
    ]

    def python(self, code, signals=(), limit=30.0):
        """Runs `code` in a fresh interpreter; returns (rc, outcome dict or None, stderr, seconds
        from the first signal to the end)."""
        prog = (
            "import json, sys, numpy as np\n"
            "import vibro\n"
            f"SCENE = {self.default!r}; CHAIN3 = {os.path.join(self.scenes, 'chain3.toml')!r}; FIG5 = {self.fig5!r}\n"
            "S = vibro.load_scene(SCENE)\n"
            "print('started', flush=True)\n"
            "try:\n"
            f"    {code}\n"
            "    print(json.dumps({'outcome': 'ok'}))\n"
            "except BaseException as e:\n"
            "    print(json.dumps({'outcome': type(e).__name__, 'message': str(e)[:500]}))\n")
        env = dict(os.environ, PYTHONPATH=self.pythonpath)
        cpu_before = children_cpu()
        p = subprocess.Popen(["/usr/bin/python3", "-c", prog], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             cwd=self.work, env=env, preexec_fn=default_stop_signals, text=True)
        clock = None
        if signals:
            # Ctrl-C once the call is under way (the interpreter printed 'started').
            line = p.stdout.readline()
            if line.strip() == "started":
                time.sleep(signals[0][0])
                p.send_signal(signals[0][1])
                clock = StopClock(p.pid)
        self.last_clock = clock
        if clock is None:
            try:
                out, err = p.communicate(timeout=limit)
            except subprocess.TimeoutExpired:
                p.kill()
                out, err = p.communicate()
                return None, None, err, None
            took = None
        else:
            out, err, hung = wait_stopping(p, clock)
            if hung:
                p.kill()
                out, err = p.communicate()
                clock.finish()
                return None, None, err, None
            took = clock.finish(children_cpu() - cpu_before)
            self.stop_walls.append((clock.wall(), took))
        outcome = None
        for line in out.splitlines()[::-1]:
            if line.startswith("{"):
                outcome = json.loads(line)
                break
        return p.returncode, outcome, err, took

    def gen_python_api(self):
        r = self.rng
        self.runs += 1
        self.categories["python-api"] = self.categories.get("python-api", 0) + 1
        if r.random() < 0.3:
            name, code = r.choice(self.PY_LONG)
            self.inputs.add(("python-long", code))
            rc, outcome, err, took = self.python(code, signals=[(r.uniform(0.1, 1.5), signal.SIGINT)], limit=60)
            full = ["python", code]
            if rc is None:
                self.find("Python ignored Ctrl-C", full, "[python-api] still running after SIGINT, " +
                          (self.last_clock.describe() if self.last_clock else "(never said 'started': no signal)"))
            elif outcome is None or outcome["outcome"] not in ("KeyboardInterrupt", "ok"):
                self.find("Python Ctrl-C gave no KeyboardInterrupt", full, f"[python-api] rc {rc} {outcome} {err[-300:]}")
            elif took is not None and took > LIVENESS and outcome["outcome"] == "KeyboardInterrupt":
                self.slow_stops.append(took)
                self.find("Python answered Ctrl-C late", full, f"[python-api] {self.last_clock.describe()}")
            return
        name, code = r.choice(self.PY_CASES)
        self.inputs.add(("python", code))
        rc, outcome, err, _ = self.python(code, limit=30)
        full = ["python", code]
        if rc is None:
            self.find("Python call ran past its limit", full, "[python-api] killed after 30 s")
        elif rc != 0 or outcome is None:
            self.find("Python interpreter crashed", full, f"[python-api] rc {rc}: {err[-400:]}")
        elif outcome["outcome"] not in ("ok", "ValueError", "TypeError", "FileNotFoundError"):
            self.find(f"Python raised {outcome['outcome']}", full, f"[python-api] {outcome.get('message')}")
        elif outcome["outcome"] == "ok" and name not in ("simulate",):
            self.find("Python accepted a bad argument", full, "[python-api] returned normally")
        elif outcome["outcome"] == "ValueError" and "\n" in outcome.get("message", ""):
            self.find("Python message spans several lines", full, f"[python-api] {outcome['message']!r}")

    # ---- two-writers ----
    def wait_for(self, path, proc, seconds=20.0):
        end = time.monotonic() + seconds
        while time.monotonic() < end and proc.poll() is None:
            if os.path.exists(path) and os.path.getsize(path) > 0:
                return True
            time.sleep(0.01)
        return False

    def gen_two_writers(self):
        r = self.rng
        self.runs += 1
        self.categories["two-writers"] = self.categories.get("two-writers", 0) + 1
        out = self.fresh(".h5")
        what = r.choice(["same-out", "same-out-force", "resume-running", "two-resumes", "basin-resume-running"])
        self.inputs.add(("two-writers", what))
        if what.startswith("basin"):
            long = ["basin", self.fig5, "--grid", "400,400", "--threads", "1", "--out", out]
        else:
            long = ["simulate", self.default, "--set", "run.periods=100000000", "--set", "run.samples_per_period=16",
                    "--out", out]
        full = [self.vibro, *long]
        if what == "two-resumes":
            first = subprocess.Popen(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=self.work,
                                     preexec_fn=default_stop_signals)
            self.wait_for(out, first)
            time.sleep(0.3)
            first.send_signal(signal.SIGTERM)
            clock = StopClock(first.pid)
            _, e, hung = wait_stopping(first, clock)
            if hung:
                first.kill()
                _, e = first.communicate()
                self.find("hang ignoring SIGTERM", full, f"[two-writers] {what}: the first run, {clock.describe()}")
                clock.finish()
                return
            clock.finish()
            a = subprocess.Popen(full + ["--resume"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=self.work,
                                 preexec_fn=default_stop_signals)
            b = subprocess.Popen(full + ["--resume"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=self.work,
                                 preexec_fn=default_stop_signals)
            procs = [a, b]
        else:
            a = subprocess.Popen(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=self.work,
                                 preexec_fn=default_stop_signals)
            if not self.wait_for(out, a):
                a.kill()
                a.communicate()
                self.find("two-writers: the first run wrote nothing", full, f"[two-writers] {what}")
                return
            extra = {"same-out": [], "same-out-force": ["--force"], "resume-running": ["--resume"],
                     "basin-resume-running": ["--resume"]}[what]
            b = subprocess.Popen(full + extra, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=self.work,
                                 preexec_fn=default_stop_signals)
            procs = [a, b]
        # The second (or one of two concurrent resumes) must be refused at once: it is given until
        # one of the two ends, up to HANG s of its own time (its test read of the file takes a while
        # on a loaded machine; a stop request sent before it ends it with exit 130, no refusal to
        # judge), or HANG_WALL s of wall time.
        waiting = StopClock(procs[-1].pid)
        while waiting.own() < HANG and waiting.wall() < HANG_WALL and all(p.poll() is None for p in procs):
            time.sleep(0.02)
        waiting.finish()
        time.sleep(r.uniform(0.2, 1.0))
        clocks = {}
        for p in procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                clocks[p.pid] = StopClock(p.pid)
        codes, errs = [], []
        for p in procs:
            clock = clocks.get(p.pid)
            if clock is None:
                _, e = p.communicate()
            else:
                _, e, hung = wait_stopping(p, clock)
                if hung:
                    p.kill()
                    _, e = p.communicate()
                    self.find("hang ignoring SIGTERM", full, f"[two-writers] {what}: {clock.describe()}")
                took = clock.finish()
                if not hung and p.returncode == 130 and took > LIVENESS:
                    self.slow_stops.append(took)
                    self.find("slow stop", full + [f"({what})"], f"[two-writers] exit 130 after {clock.describe()}")
            codes.append(p.returncode)
            errs.append(e.decode(errors="replace"))
        refused = [i for i, c in enumerate(codes) if c == 2 and "in use" in errs[i]]
        if len(refused) != 1:
            self.find("a second writer was not refused", full + [f"({what})"],
                      f"[two-writers] exits {codes}: {[e[-200:] for e in errs]}")
        for i, c in enumerate(codes):
            if c not in (0, 2, 130):
                self.find(f"exit {c}", full + [f"({what})"], f"[two-writers] {errs[i][-300:]}")
        try:
            with h5py.File(out, "r") as f:
                status = f.attrs.get("status")
                status = status.decode() if isinstance(status, bytes) else status
                if status not in ("interrupted", "ok"):
                    self.find("two-writers: the file says neither ok nor interrupted", full, f"[two-writers] {status}")
                for name in ("events/t", "section/t", "basin/labels"):
                    if name in f:
                        f[name][:]
        except OSError as e:
            self.find("two-writers: the file is unreadable", full + [f"({what})"], f"[two-writers] {e}")

    # ---- full-disk ----
    def mount_tmpfs(self):
        d = self.fresh(".mnt")
        os.mkdir(d)
        p = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=3m", "tmpfs", d], capture_output=True)
        return d if p.returncode == 0 else None

    def gen_full_disk(self):
        r = self.rng
        if self.can_mount is False:
            return False
        d = self.mount_tmpfs()
        self.can_mount = d is not None
        if d is None:
            return False
        try:
            out = os.path.join(d, "out.h5")
            what = r.choice(["simulate", "simulate-samples", "basin", "sweep", "continue", "extend", "extend"])
            if what == "extend":  # a stored run on the small disk, then extended until the disk is full
                scene = r.choice([self.default, os.path.join(self.scenes, "contacts_two_sided_1dof.toml"), self.chain2])
                self.make(["simulate", scene, "--set", "run.periods=50", "--set", "run.samples_per_period=64", "--out",
                           out], out)
            argv = {
                "simulate": ["simulate", self.default, "--set", "run.periods=3000000", "--out", out],
                "simulate-samples": ["simulate", self.chain2, "--set", "run.periods=3000000", "--set",
                                     "run.samples_per_period=256", "--out", out],
                "basin": ["basin", self.fig5, "--grid", "300,300", "--threads", "1", "--out", out],
                "sweep": ["sweep", self.fig5, "--param", "excitation.frequency", "--from", "1", "--to", "3",
                          "--steps", "100000", "--out", out],
                "continue": ["continue", os.path.join(self.scenes, "chain3.toml"), "--param", "excitation.frequency",
                             "--to", "0.3", "--step", "1e-5", "--max-points", "1000000", "--out", out],
                "extend": ["simulate", scene if what == "extend" else "", "--set", "run.samples_per_period=64", "--out",
                           out, "--extend", "3000000"] if what == "extend" else [],
            }[what]
            if r.random() < 0.3:  # the disk nearly full before the run
                try:
                    with open(os.path.join(d, "filler"), "wb") as f:
                        f.write(b"\0" * r.choice([2_900_000, 3_000_000, 3_145_000]))
                except OSError:  # already full (the stored run to extend takes its share): as wanted
                    pass
            rc, err = self.run("full-disk", argv, limit=40, out=None, key=what)
            full = [self.vibro, *argv]
            # "no space", or simulate's pace check before the disk fills ("its disk has 1.5 MB free")
            if rc == 3 and "space" not in err.lower() and "its disk has" not in err:
                self.find("full disk: exit 3 without saying so", full, f"[full-disk] {err[-300:]}")
            if os.path.exists(out) and rc in (0, 3, 130):
                try:
                    with h5py.File(out, "r") as f:
                        for name in ("events/t", "section/t", "samples/t", "basin/labels", "branch/value"):
                            if name in f:
                                f[name][:]
                except OSError as e:
                    self.find("full disk: the file kept is unreadable", full, f"[full-disk] exit {rc}: {e}")
                if what == "extend":
                    i = subprocess.run([self.vibro, "info", out], capture_output=True, text=True, timeout=120)
                    if i.returncode != 0:
                        self.find("full disk: the extended file is unreadable by vibro info", full,
                                  f"[full-disk] exit {rc}; info: {i.stderr[-300:]}")
        finally:
            subprocess.run(["umount", "-l", d], capture_output=True)
        return True

    # ---- several contacts: partition, check, sweep, attractors ----
    def gen_contacts(self):
        r = self.rng
        scene = os.path.join(self.scenes, r.choice(["contacts_two_sided_1dof.toml", "contacts_chain2.toml",
                                                     "contacts_impact_pair.toml", "contacts_beam3.toml",
                                                     "contacts_preload_clearance_1dof.toml",
                                                     "contacts_chain2_modal.toml"]))
        what = r.choice(["partition", "check", "sweep", "attractors"])
        num = lambda: r.choice(["0.5", "1", "1.2", "2.5", "-1", "0", "1e300", "nan", "3"])
        out = self.fresh(".h5")
        if what == "partition":
            argv = ["partition", scene, "--params", r.choice(["excitation.amplitude,excitation.frequency",
                                                              "excitation.frequency,excitation.amplitude",
                                                              "contact[0].position,excitation.amplitude",
                                                              "contact[1].restitution,excitation.frequency"]),
                    "--range1", f"{num()},{num()}", "--range2", f"{num()},{num()}", "--steps1", r.choice(["1", "2", "0"]),
                    "--sticking-fraction", r.choice(["0.3", "0.1,0.5", "2", "-1"]), "--threads", "1", "--out", out]
        elif what == "check":
            argv = ["check", scene, "--set", f"run.periods={r.choice([5, 20, 60])}"] + \
                   (["--precision", "quad"] if r.random() < 0.2 else [])
        elif what == "sweep":
            argv = ["sweep", scene, "--param", r.choice(["excitation.frequency", "excitation.amplitude",
                                                         "contact[0].restitution", "contact[1].position"]),
                    "--from", num(), "--to", num(), "--steps", r.choice(["3", "8", "0"]), "--record",
                    r.choice(["1", "4"]), "--out", out] + (["--one-way"] if r.random() < 0.5 else [])
        else:
            argv = ["attractors", scene, "--samples", r.choice(["4", "12", "0"]), "--threads", "1",
                    "--seed", str(r.randrange(100))] + (["--x", r.choice(["x_B", "v_B", "X1", "V1", "X9"])]
                                                        if r.random() < 0.4 else [])
        if r.random() < 0.3:
            argv += ["--time-limit", r.choice(["0.5", "2", "0"])]
        signals = [(r.uniform(0.05, 2.0), r.choice([signal.SIGINT, signal.SIGTERM]))] if r.random() < 0.25 else []
        rc, err = self.run("contacts", argv, signals=signals, limit=60, out=None, key=what)
        if rc == 3 and "--time-limit" in argv and "time limit" not in err and "out of" not in err and \
                "stopped" not in err and "failed" not in err.lower() and "could not" not in err:
            self.find("contacts: exit 3 without one line saying why", [self.vibro, *argv], f"[contacts] {err[-300:]}")
        if os.path.exists(out) and rc in (0, 3, 130):
            i = subprocess.run([self.vibro, "info", out], capture_output=True, text=True, timeout=120)
            if i.returncode != 0:
                self.find("contacts: the --out file kept is unreadable", [self.vibro, *argv],
                          f"[contacts] exit {rc}; info: {i.stderr[-300:]}")

    # ---- malformed sequence / contact columns ----
    def gen_sequence_column(self):
        r = self.rng
        garbage = lambda: r.choice(["", "A", "ZZ", "0", "01", "0;1", "0 1", "10", "-1", "\u00e9\u00e9", "nan", "1e9",
                                    "0" * 5000, "x\ty", "\"0,1\"", "0,1", "below above", "c0c1", "\x01", "[]"])
        if r.random() < 0.6:
            header, rows = read_csv(self.seed_files["branch_seq_csv"])
            rows = [list(x) for x in rows]
            if "sequence" not in header:
                header, rows = header + ["sequence"], [x + [""] for x in rows]
            j = header.index("sequence")
            for i in range(len(rows)):
                if r.random() < 0.5:
                    rows[i][j] = garbage()
            if r.random() < 0.1:
                header, rows = header + ["sequence"], [x + [x[j]] for x in rows]
            path = self.fresh(".csv")
            write_csv(path, header, rows)
            argv = ["validate", os.path.join(self.scenes, "contacts_two_sided_1dof.toml"), path, "--param",
                    "excitation.amplitude"] + (["--json"] if r.random() < 0.5 else [])
        else:
            header, rows = read_csv(self.seed_files["events_contacts_csv"])
            rows = [list(x) for x in rows]
            if "contact" not in header:
                header, rows = header + ["contact"], [x + ["0"] for x in rows]
            j = header.index("contact")
            for i in range(len(rows)):
                if r.random() < 0.3:
                    rows[i][j] = r.choice([garbage(), "2", "-1", "0.5", "1e300", "", "1"])
            path = self.fresh(".csv")
            write_csv(path, header, rows)
            argv = ["score", os.path.join(self.scenes, "contacts_two_sided_1dof.toml"), path,
                    "--set", "run.periods=6"] + (["--json"] if r.random() < 0.5 else [])
        rc, err = self.run("sequence-column", argv, limit=60, out=None, key=argv[0], content=open(path, "rb").read())
        if rc == 2:
            first = err.strip().splitlines()[0] if err.strip() else ""
            if path not in first and "sequence" not in first and "contact" not in first:
                self.find("sequence column: exit 2 not located", [self.vibro, *argv], f"[sequence-column] {err[-400:]}")

    # ---- --extend under a file-size limit ----
    def gen_extend_fsize(self):
        r = self.rng
        scene = r.choice([self.default, os.path.join(self.scenes, "contacts_two_sided_1dof.toml")])
        out = self.fresh(".h5")
        self.make(["simulate", scene, "--set", "run.periods=50", "--out", out], out)
        size = os.path.getsize(out)
        blocks = max(1, (size + r.choice([0, 4096, 65536, 1 << 20])) // 1024)  # ulimit -f counts 1024-byte blocks
        argv = [self.vibro, "simulate", scene, "--out", out, "--extend", str(r.choice([1000, 100000, 1000000]))]
        def limited():
            default_stop_signals()
            import resource
            resource.setrlimit(resource.RLIMIT_FSIZE, (blocks * 1024, blocks * 1024))
        self.runs += 1
        self.categories["extend-fsize"] = self.categories.get("extend-fsize", 0) + 1
        self.inputs.add(("extend-fsize", scene, blocks))
        p = subprocess.run(argv, capture_output=True, text=True, timeout=300, preexec_fn=limited)
        self.exits[p.returncode] = self.exits.get(p.returncode, 0) + 1
        if p.returncode not in (0, 3):
            self.find("extend under ulimit -f: exit neither 0 nor 3", argv,
                      f"[extend-fsize] ulimit -f {blocks}: exit {p.returncode}: {p.stderr[-400:]}")
        elif p.returncode == 3 and not any(w in p.stderr for w in ("too large", "space", "file-size limit")):
            self.find("extend under ulimit -f: exit 3 without naming the limit", argv, f"[extend-fsize] {p.stderr[-300:]}")
        i = subprocess.run([self.vibro, "info", out], capture_output=True, text=True, timeout=120)
        if i.returncode != 0:
            self.find("extend under ulimit -f: the file kept is unreadable", argv,
                      f"[extend-fsize] exit {p.returncode}; info: {i.stderr[-300:]}")

    # ---- compliant stops: stiffness, damping, separation on [stop] and [[contact]] ----
    COMPLIANT_1DOF = (
        "title = \"fuzz: a compliant stop\"\n[structure]\nmass = [[1.0]]\nstiffness = [[1.0]]\nforcing_dof = 0\n"
        "contact_dof = 0\ndamping_ratios = [{zeta}]\n[excitation]\namplitude = {amp}\nfrequency = {freq}\n"
        "[stop]\nposition = {pos}\n{keys}[initial]\ndisplacement = [0.0]\nvelocity = [{v0}]\n[run]\nperiods = {periods}\n")
    # Each pool: the values a scene may hold, then (after None) those it must not or may not.
    STIFFNESS = ["1.0", "100.0", "1e4", "1e8", "1e12", "1e-8", "1e16", "3.5", None, "0", "-1.0", "nan", "inf", "1e308",
                 "5e-324", "\"x\"", "true", "[1.0]", "-0.0"]
    DAMPING = ["0", "0.1", "2.0", "10.0", "1e6", "1e-300", "0.5", None, "-0.1", "nan", "inf", "1e308", "-0.0", "\"x\""]
    SEPARATION = ["\"force\"", "\"gap\"", None, "\"Force\"", "\"\"", "1", "\"none\"", "\"gap \""]

    def pick(self, pool):
        """A value of the pool: one it may hold three times in four."""
        k = pool.index(None)
        return self.rng.choice(pool[:k] if self.rng.random() < 0.75 else pool[k + 1:])
    # `check` takes a compliant stop since CVODE integrates its contact phase (docs/compliant.md): it is
    # drawn as one of the commands that must run, with `--precision quad` as one that must refuse;
    # `orbit` too, since the Poincaré solver follows a contact phase (docs/compliant.md, "Periodic orbits"),
    # and `continue`, the same map along a branch ("Along a continued branch").
    RIGID_ONLY = ["prove", "validate", "score", "basin", "attractors", "sweep",
                  "partition", "curve", "diagram", "check-quad"]

    @staticmethod
    def compliance_valid(k, c, sep, restitution):
        """True: a scene vibro must accept; False: one it must refuse (docs/compliant.md); None:
        not promised either way (an infinite stiffness, a subnormal one)."""
        def num(s):
            try:
                return float(s)
            except (TypeError, ValueError):
                return None
        if k is None:
            return False if (c is not None or sep is not None) else True
        kv = num(k)
        if kv is None or kv != kv or kv <= 0 or k in ("true",):
            return False
        if restitution is not None:
            return False
        if c is not None:
            cv = num(c)
            if cv is None or cv != cv or cv < 0:
                return False
        if sep is not None and sep not in ("\"force\"", "\"gap\""):
            return False
        # Every magnitude of a scene is at most 1e100 (docs/compliant.md, docs/reliability.md).
        if kv > 1e100 or (c is not None and float(c) > 1e100):
            return False
        if kv < 1e-300:
            return None
        return True

    def gen_compliant(self):
        r = self.rng
        form = r.choice(["stop", "stop", "contacts", "sdnd121"])
        sets = []
        k = c = sep = rest = None
        if form == "stop":
            k = self.pick(self.STIFFNESS) if r.random() < 0.9 else None
            c = self.pick(self.DAMPING) if r.random() < 0.6 else None
            sep = self.pick(self.SEPARATION) if r.random() < 0.5 else None
            rest = r.choice(["0.8", "1.0"]) if r.random() < 0.1 else None
            keys = "".join(f"{name} = {v}\n" for name, v in (("stiffness", k), ("damping", c), ("separation", sep),
                                                             ("restitution", rest)) if v is not None)
            text = self.COMPLIANT_1DOF.format(zeta=r.choice(["0.0", "0.02"]), amp=r.choice(["0.5", "1.0", "3.0"]),
                                              freq=r.choice(["0.8", "1.0", "2.8"]), pos=r.choice(["0.0", "-0.5", "-0.05"]),
                                              keys=keys, v0=r.choice(["0.0", "1.0"]), periods=r.choice([5, 20, 60]))
            scene = self.write_scene(text)
            valid = self.compliance_valid(k, c, sep, rest)
            if k is None and rest is None and valid is True:
                valid = None  # a stop with a position only: whatever the default restitution is
        elif form == "contacts":
            scene = os.path.join(self.scenes, "tube_compliant_support.toml")
            j = r.choice([0, 1, 1, 2])
            valid = True
            for name, pool in (("stiffness", self.STIFFNESS), ("damping", self.DAMPING), ("separation", self.SEPARATION)):
                if r.random() < 0.5:
                    v = self.pick(pool)
                    sets += ["--set", f"contact[{j}].{name}={v}"]
                    if j == 2:
                        valid = False  # the scene has two contacts
                    else:
                        kk = v if name == "stiffness" else "1000.0"
                        cc = v if name == "damping" else "2.0"
                        ss = v if name == "separation" else "\"force\""
                        ok = self.compliance_valid(kk, cc, ss, None)
                        valid = ok if valid is not False and ok is not True else valid
            if r.random() < 0.1 and j < 2:
                sets += ["--set", f"contact[{j}].restitution=0.7"]
                valid = False
            sets += ["--set", f"run.periods={r.choice([5, 20])}"]
        else:
            scene = os.path.join(self.scenes, "sdnd121_compliant.toml")
            valid = True
            for name, pool in (("stiffness", self.STIFFNESS), ("damping", self.DAMPING), ("separation", self.SEPARATION)):
                if r.random() < 0.4:
                    v = self.pick(pool)
                    sets += ["--set", f"stop.{name}={v}"]
                    ok = self.compliance_valid(v if name == "stiffness" else "1e10", v if name == "damping" else None,
                                               v if name == "separation" else None, None)
                    valid = ok if valid is not False and ok is not True else valid
        cmd = r.choice(["simulate"] * 6 + ["model"] * 2 + ["rigid-beside"] * 3 + ["check", "orbit", "continue"]) if r.random() < 0.75 else \
            r.choice(self.RIGID_ONLY)
        out = self.fresh(".h5")
        if cmd == "simulate":
            argv = ["simulate", scene, *sets] + (["--out", out] if r.random() < 0.6 else [])
            if r.random() < 0.3:
                argv += ["--blocks", r.choice(["2", "10", "1", "100001"])]
            if r.random() < 0.15:
                if r.random() < 0.5:
                    argv += ["--set", 'run.precision="quad"']
                    valid = False if valid is not None else None
                else:  # CVODE integrates a compliant contact phase too
                    argv += ["--set", 'run.engine="cvode"']
        elif cmd == "rigid-beside":
            argv = ["simulate", scene, *sets, "--rigid-beside", "--json"] + (["--out", out] if r.random() < 0.3 else [])
        elif cmd == "model":
            argv = ["model", scene, *sets] + (["--json"] if r.random() < 0.5 else [])
        elif cmd == "check":
            argv = ["check", scene, *sets] + (["--json"] if r.random() < 0.5 else [])
        else:
            argv = {"orbit": ["orbit", scene, "--out", out], "continue": ["continue", scene, "--param",
                    "excitation.amplitude", "--to", "1.2", "--max-points", "3", "--out", out],
                    "prove": ["prove", scene], "check-quad": ["check", scene, "--precision", "quad"],
                    "validate": ["validate", scene, self.seed_files["branch_csv"], "--param", "excitation.amplitude"],
                    "score": ["score", scene, self.seed_files["events_csv"]],
                    "basin": ["basin", scene, "--grid", "3,3", "--threads", "1", "--out", out],
                    "attractors": ["attractors", scene, "--samples", "4", "--threads", "1"],
                    "sweep": ["sweep", scene, "--param", "excitation.frequency", "--from", "1", "--to", "2", "--steps",
                              "3", "--out", out],
                    "partition": ["partition", scene, "--params", "excitation.amplitude,excitation.frequency",
                                  "--range1", "0.5,1", "--range2", "1,2", "--steps1", "2", "--sticking-fraction", "0.3",
                                  "--threads", "1", "--out", out],
                    "curve": ["curve", scene, "--param", "excitation.frequency,excitation.amplitude", "--kind",
                              "grazing", "--range1", "0.5,3", "--range2", "0.1,3", "--toward", "2,2",
                              "--max-points", "3", "--out", out],
                    "diagram": ["diagram", scene, "--param", "excitation.frequency", "--from", "1", "--to", "2",
                                "--out", out]}[cmd]
            argv = argv[:2] + sets + argv[2:]
        argv += ["--time-limit", "30"]
        signals = [(r.uniform(0.1, 1.5), r.choice([signal.SIGINT, signal.SIGTERM]))] if r.random() < 0.1 else []
        rc, err = self.run("compliant", argv, signals=signals, limit=90, watch=[self.work],
                           out=out if "--out" in argv else None, key=(form, cmd, k, c, sep, rest, tuple(sets)))
        full = [self.vibro, *argv]
        if cmd in self.RIGID_ONLY and rc not in (2, 130):
            self.find(f"compliant: {cmd} not refused", full, f"[compliant] exit {rc}: {err[-300:]}")
        elif rc in (0, 3) and valid is False:
            self.find("compliant: accepted a stop it must refuse", full, f"[compliant] exit {rc}: {err[-300:]}")
        elif rc == 2 and valid is True and cmd in ("simulate", "model", "check", "orbit", "continue") and "cvode" not in " ".join(argv) \
                and "quad" not in " ".join(argv) and "--blocks" not in argv:
            self.find("compliant: refused a valid stop", full, f"[compliant] {err[-300:]}")
        if cmd == "rigid-beside" and rc == 0:
            try:
                doc = json.loads(self.last_stdout)
                assert "rigid_model" in doc
            except (ValueError, AssertionError):
                self.find("--rigid-beside --json without rigid_model", full, f"[compliant] {self.last_stdout[-300:]}")
        # `vibro orbit` says why on its status line (stdout), its stderr giving what to try next.
        said_by_orbit = cmd == "orbit" and any(l.startswith("status") and ":" in l for l in self.last_stdout.splitlines())
        # `vibro continue` says why its branch ended on its `end` line (stdout).
        said_by_orbit = said_by_orbit or (cmd == "continue" and any(l.startswith("end ") for l in self.last_stdout.splitlines()))
        if rc == 3 and "--rigid-beside" not in argv and not said_by_orbit and \
                not any(w in err for w in ("time limit", "out of", "per time unit", "numerical", "undetermined",
                                           "failed", "could not", "stopped")):
            self.find("compliant: exit 3 without saying why", full, f"[compliant] {err[-300:]}")

    # ---- sums of harmonics: [excitation] lists and vectors ----
    def harmonics_block(self, ndof):
        """An [excitation] block of lists and whether vibro must accept it (True), refuse it (False)
        or either (None), from docs/harmonics.md's constraints."""
        r = self.rng
        n = r.choice([1, 1, 2, 2, 3, 4])
        valid = True
        amps = [r.choice(["0.8", "0.3", "0.5", "0.0"]) for _ in range(n)]
        base = r.choice([0.8, 1.0, 2.5])
        mult = [1] + [r.choice([2, 3, 0.5, 1.5, 1, 7]) for _ in range(n - 1)]
        freqs = [repr(base * m) for m in mult]
        phases = [r.choice(["0.0", "0.5", "-3.0"]) for _ in range(n)]
        vectors = None
        if r.random() < 0.5:
            vectors = [[r.choice(["1.0", "0.0", "0.5"]) for _ in range(ndof)] for _ in range(n)]
            for v in vectors:
                if all(float(x) == 0 for x in v):
                    valid = False
        damage = r.choice(["none", "none", "none", "length", "freq", "amp", "irrational", "vector-length",
                           "vector-bad", "phase", "scalar-beside", "empty", "many", "ratio-1000"])
        if damage == "length":  # (amplitudes or frequencies: the phases are not always written)
            r.choice([amps, freqs]).append("0.1")
            valid = False
        elif damage == "freq":
            freqs[r.randrange(n)] = r.choice(["0.0", "-1.0", "nan", "inf", "\"x\"", "-0.0"])
            valid = False
        elif damage == "amp":
            amps[r.randrange(n)] = r.choice(["-0.1", "nan", "inf", "\"x\""])
            valid = False
        elif damage == "irrational" and n > 1:
            freqs[-1] = repr(base * math.pi)
            valid = False
        elif damage == "ratio-1000" and n > 1:
            freqs[-1] = repr(base * r.choice([1001, 101 / 100 * 0 + 1009]))  # T past 1000 periods of it
            valid = False
        elif damage == "vector-length":
            vectors = [["1.0"] * (ndof + r.choice([-1, 1])) for _ in range(n)]
            valid = False if ndof > 0 else None
        elif damage == "vector-bad":
            vectors = [["1.0"] * ndof for _ in range(n)]
            vectors[r.randrange(n)][0] = r.choice(["nan", "inf"])
            if ndof == 1 or r.random() < 0.5:
                vectors[0] = ["0.0"] * ndof
            valid = False
        elif damage == "phase":
            phases[r.randrange(n)] = r.choice(["nan", "inf", "1e300"])
            valid = None
        elif damage == "scalar-beside" and n > 1:
            amps = amps[0]
            valid = False
        elif damage == "empty":
            amps, freqs, phases = [], [], []
            vectors = None
            valid = False
        elif damage == "many":
            amps, freqs, phases = ["0.01"] * 5000, [repr(base)] * 5000, ["0.0"] * 5000
            vectors = None
            valid = None
        if all(a == "0.0" for a in (amps if isinstance(amps, list) else [amps])) and valid:
            valid = None
        lst = lambda xs: xs if isinstance(xs, str) else "[" + ", ".join(xs) + "]"
        text = f"[excitation]\namplitude = {lst(amps)}\nfrequency = {lst(freqs)}\n"
        if r.random() < 0.6:
            text += f"phase = {lst(phases)}\n"
        if vectors is not None:
            text += "vectors = [" + ", ".join(lst(v) for v in vectors) + "]\n"
        return text, valid, damage

    @staticmethod
    def replace_table(text, table, block):
        """The scene text with its [table] (up to the next table) replaced by block."""
        out, skip = [], False
        for line in text.split("\n"):
            s = line.strip()
            if s.startswith("["):
                skip = s == f"[{table}]"
                if skip:
                    out.append(block.rstrip("\n"))
                    continue
            if not skip:
                out.append(line)
        return "\n".join(out)

    def gen_harmonics(self):
        r = self.rng
        name = r.choice(["two_harmonics_chain2.toml", "chain2.toml", "fig08_preload.toml", "default.toml",
                         "contacts_two_sided_1dof.toml", "fig05_coexistence.toml", "sdnd121_compliant.toml"])
        text = self.scene_texts[name]
        ndof = 2 if "chain2" in name else 1
        block, valid, damage = self.harmonics_block(ndof)
        text = self.replace_table(text, "excitation", block)
        if name == "sdnd121_compliant.toml" and valid is True:
            valid = None  # a compliant stop under a sum of harmonics: refused before 6ceea5c, run since
        path = self.write_scene(text)
        cmd = r.choice(["simulate"] * 5 + ["model", "orbit", "continue", "sweep", "basin", "attractors", "prove", "check"])
        out = self.fresh(".h5")
        argv = {"simulate": ["simulate", path, "--set", f"run.periods={r.choice([3, 20])}", "--out", out],
                "model": ["model", path],
                "orbit": ["orbit", path, "--out", out],
                "continue": ["continue", path, "--param", r.choice(["excitation.amplitude", "excitation.frequency"]),
                             "--to", "1.1", "--max-points", "3", "--out", out],
                "sweep": ["sweep", path, "--param", "excitation.frequency", "--from", "0.8", "--to", "1.0", "--steps",
                          "3", "--out", out],
                "basin": ["basin", path, "--grid", "3,3", "--threads", "1", "--out", out],
                "attractors": ["attractors", path, "--samples", "4", "--threads", "1"],
                "prove": ["prove", path, "--time-limit", "10"],
                "check": ["check", path, "--set", "run.periods=10"]}[cmd]
        if "--time-limit" not in argv:
            argv += ["--time-limit", "40"]
        if r.random() < 0.3:
            argv += ["--json"]
        rc, err = self.run("harmonics", argv, limit=90, watch=[self.work], out=out if "--out" in argv else None,
                           key=(name, cmd), content=block)
        full = [self.vibro, *argv]
        if valid is False and rc in (0, 3, 4):
            self.find("harmonics: accepted an [excitation] it must refuse", full,
                      f"[harmonics] {damage}: exit {rc}; block:\n{block[:600]}")
        if valid is True and rc == 2 and cmd in ("simulate", "model") and name != "sdnd121_compliant.toml":
            self.find("harmonics: refused a valid [excitation]", full, f"[harmonics] {damage}: {err[-400:]}\n{block[:600]}")

    def gen_harmonics_equivalence(self):
        """One harmonic written as lists (and its forcing vector e_A, phase 0) runs to the bit as
        the scalar scene (docs/harmonics.md): the JSON summaries agree except for timings."""
        r = self.rng
        name = r.choice(["chain2.toml", "fig08_preload.toml", "default.toml", "fig05_coexistence.toml",
                         "contacts_two_sided_1dof.toml", "chain3.toml"])
        text = self.scene_texts[name]
        amp = r.choice(["0.5", "1.0", "1.25", "2.0"])
        freq = r.choice(["0.8", "1.0", "2.8", "2.5"])
        sets = ["--set", f"excitation.amplitude={amp}", "--set", f"excitation.frequency={freq}"]
        scalar = self.write_scene(text)
        import tomllib
        try:
            doc = tomllib.loads(text)
        except tomllib.TOMLDecodeError:
            return
        n = len(doc["structure"]["mass"]) if "mass" in doc["structure"] else len(doc["structure"].get("frequencies", [0]))
        fdof = doc["structure"].get("forcing_dof", 0)
        e = ["1.0" if i == fdof else "0.0" for i in range(n)]
        block = f"[excitation]\namplitude = [{amp}]\nfrequency = [{freq}]\nphase = [0.0]\n"
        if "mass" in doc["structure"] and r.random() < 0.5:
            block += "vectors = [[" + ", ".join(e) + "]]\n"
        listed = self.write_scene(self.replace_table(text, "excitation", block))
        periods = ["--set", f"run.periods={r.choice([10, 40])}"]
        outs = []
        for path, extra in ((scalar, sets), (listed, [])):
            argv = ["simulate", path, *extra, *periods, "--json", "--time-limit", "60"]
            rc, err = self.run("harmonics", argv, limit=90, watch=[self.work], key=("equiv", name, amp, freq))
            outs.append((rc, self.last_stdout, err))
        (rc1, o1, e1), (rc2, o2, e2) = outs
        def strip(o):
            try:
                d = json.loads(o)
            except ValueError:
                return o
            for key in ("seconds", "wall_time", "cpu_time", "elapsed", "scene", "path", "time_s", "work"):
                d.pop(key, None)
            return json.dumps(d, sort_keys=True)
        if rc1 != rc2 or (rc1 == 0 and strip(o1) != strip(o2)):
            a, b = strip(o1), strip(o2)
            k = next((i for i in range(min(len(a), len(b))) if a[i] != b[i]), min(len(a), len(b)))
            self.find("harmonics: one harmonic as a list differs from the scalar scene",
                      [self.vibro, "simulate", listed, *periods, "--json"],
                      f"[harmonics] {name} a={amp} w={freq}: exits {rc1}/{rc2}; first difference at {k}: "
                      f"{a[max(0, k - 80):k + 80]!r} vs {b[max(0, k - 80):k + 80]!r}; {e2[-200:]}")

    # ---- vibro curve ----
    def gen_curve(self):
        """`vibro curve` from docs/diagram.md's two examples (the sticking-lost curve of Fig. 9 toward a
        point; the pitchfork curve from a stored branch, damaged as from-branch damages them), each
        option replaced by a corner value now and then; a tiny --time-limit or a stop signal."""
        r = self.rng
        num = lambda: r.choice(["0.5", "1", "1.5", "2.8", "3", "12", "20", "-1", "0", "nan", "inf", "1e300", "1e-300"])
        kinds = ["fold", "flip", "neimark-sacker", "branch-point", "grazing", "sticking-lost", "sticking-entry",
                 "rising", "simultaneous"]
        out = self.fresh(".h5")
        opts = {}
        watch = []
        if r.random() < 0.55:
            scene = os.path.join(self.scenes, "fig08_preload.toml")
            opts = {"--param": "excitation.frequency,excitation.amplitude", "--kind": "sticking-lost",
                    "--range1": "1,20", "--range2": "1,12", "--toward": "2.8,1.5"}
            variants = {"--param": ["excitation.amplitude,excitation.frequency", "excitation.frequency,excitation.frequency",
                                    "stop.restitution,excitation.amplitude", "x,y", "excitation.frequency"],
                        "--kind": kinds + ["sticking-lost,fold", "nonsense", ""],
                        "--range1": [f"{num()},{num()}", "20,1", "1,1"], "--range2": [f"{num()},{num()}", "12,1"],
                        "--toward": [f"{num()},{num()}", "2.8", "2.8,1.5,3,1"], "--orbit": ["auto", "sticking", "impact", "x"],
                        "--period": ["1", "2", "0", "-1", "1000000"], "--transient": ["0", "10", "100000000"],
                        "--contact": ["0", "1", "-1"]}
        else:
            scene = self.pitchfork
            path, what, valid = self.damaged_branch(-1, seed="branch_bif") if r.random() < 0.5 else \
                (self.seed_files["branch_bif"], "untouched", True)
            watch = [path]
            opts = {"--param": "excitation.amplitude,excitation.frequency", "--from": path, "--point": "0",
                    "--range1": "0,5", "--range2": "1.5,4"}
            variants = {"--param": ["excitation.frequency,excitation.amplitude", "contact[0].restitution,excitation.amplitude",
                                    "excitation.amplitude,contact[2].position"],
                        "--point": ["1", "-1", "99", "x"], "--range1": [f"{num()},{num()}"],
                        "--range2": [f"{num()},{num()}"], "--kind": kinds + ["x"], "--contact": ["0", "1", "2", "-1"],
                        "--toward": ["3,2"]}
        for _ in range(r.choice([0, 0, 1, 1, 2])):
            k = r.choice(sorted(variants))
            opts[k] = r.choice(variants[k])
        opts["--step"] = r.choice(["0.05"] * 6 + ["0.1", "1e-6", "0", "-0.1", "nan", "2"])
        opts["--max-points"] = r.choice(["2", "3", "5", "3", "2", "0"])
        argv = ["curve", scene]
        for k, v in opts.items():
            argv += [k, v]
        argv += ["--out", out] + (["--json"] if r.random() < 0.4 else [])
        argv += ["--time-limit", r.choice(["0.5", "10", "30", "30"])]
        signals = [(r.uniform(0.1, 2.0), r.choice([signal.SIGINT, signal.SIGTERM]))] if r.random() < 0.2 else []
        rc, err = self.run("curve", argv, signals=signals, limit=90, watch=[*watch, self.work], out=None,
                           key=tuple(a if not a.startswith(self.work) else "<tmp>" for a in argv[2:]))
        full = [self.vibro, *argv]
        if rc == 3 and not any(w in err for w in ("time limit", "end", "out of", "could not", "no ", "failed")) \
                and "end" not in self.last_stdout:
            self.find("curve: exit 3 without saying why", full, f"[curve] {err[-300:]} {self.last_stdout[-300:]}")
        if os.path.exists(out) and rc in (0, 3, 130):
            i = subprocess.run([self.vibro, "info", out], capture_output=True, text=True, timeout=120)
            if i.returncode != 0:
                self.find("curve: the --out file kept is unreadable", full, f"[curve] exit {rc}; info: {i.stderr[-300:]}")

    # ---- prove --bifurcation ----
    def gen_prove_bifurcation(self):
        r = self.rng
        out = os.path.join(self.work, f"bif{self.runs}.json")
        mode = r.choice(["branch", "branch", "value", "value-from"])
        valid = None
        if mode == "branch":
            path, what, valid = self.damaged_branch(-1, seed="branch_bif")
            # The point is read from the branch's bifurcations and its parameter: damage elsewhere
            # (the states, another dataset) need not be refused, only never make a false proof.
            valid = True if what == "untouched" else None
            point = r.choice(["0", "0", "1", "-1", "99", "x"])
            argv = ["prove", self.pitchfork, "--bifurcation", path] + (["--point", point] if point != "0" or r.random() < 0.5
                                                                       else [])
            if point != "0":
                valid = False if point in ("-1", "99", "x") else None
            key = (what, point)
            watch = [path]
        else:
            kind = r.choice(["branch-point", "branch-point", "fold", "grazing", "flip", "pitchfork", "", "x"])
            key_ = r.choice(["excitation.amplitude", "excitation.amplitude", "excitation.frequency", "stop.position",
                             "contact[0].restitution", "nope", ""])
            value = r.choice([repr(self.bif_value), repr(self.bif_value + 1e-9), repr(self.bif_value - 1e-9), "3.3",
                              "nan", "inf", "1e300", "-3.28", "", "0x1p1", "3.2860503573579969e0"])
            spec = r.choice([f"{kind}:{key_}={value}", f"{kind}{key_}={value}", f"{kind}:{key_}{value}",
                             f"{kind}:{key_}={value}"])
            argv = ["prove", self.pitchfork, "--bifurcation", spec]
            if mode == "value-from":
                path, what, _ = self.damaged_branch(-1, seed="branch_bif")
                argv += ["--from", path]
                watch = [path]
            else:
                what, watch = "none", []
            key = (spec, what)
        argv += ["--out", out]
        if r.random() < 0.4:
            argv.append("--json")
        limited = r.random() < 0.2
        if limited:
            argv += ["--time-limit", r.choice(["0.001", "0.05", "0.5"])]
        signals = [(r.uniform(0.05, 1.5), r.choice([signal.SIGINT, signal.SIGTERM]))] if r.random() < 0.2 else []
        rc, err = self.run("prove-bifurcation", argv, signals=signals, limit=180, watch=watch, key=key)
        full = [self.vibro, *argv]
        if rc == 0 and valid is False:
            self.find("prove --bifurcation accepted an input it must refuse", full, f"[prove-bifurcation] {key}: exit 0")
        if valid is True and not limited and not signals and rc != 0:
            self.find("prove --bifurcation did not prove the untouched branch's pitchfork", full,
                      f"[prove-bifurcation] exit {rc}: {err[-300:]} {self.last_stdout[-300:]}")
        if rc == 130 and os.path.exists(out):
            self.find("prove --bifurcation interrupted wrote a certificate", full, "[prove-bifurcation]")
        if os.path.exists(out):
            code, line, err2 = self.check_certificate(out)
            if code is None:
                self.find("the checker failed on a certificate file", full, f"[prove-bifurcation] {line} {err2}")
            elif rc == 0 and code != 0:
                self.find("a proven bifurcation that the checker does not confirm", full, f"[prove-bifurcation] {line}")
            elif rc == 4 and code == 0 and "confirmed: every" in line:
                pass  # a certificate of "not proven" is confirmed as such
            if code is not None and self.rng.random() < 0.5 and len(self.certificates) < 40:
                keep = self.fresh(".json")
                shutil.copy(out, keep)
                self.certificates.append(keep)
            os.remove(out)
        elif rc in (0, 4) and "--out" in argv and not limited:
            self.find("prove --bifurcation --out wrote no certificate", full, f"[prove-bifurcation] exit {rc}")

    # ---- certificates given to the checker ----
    def check_certificate(self, path, vlimit=None):
        """(exit code, its one line, stderr) of the checker on `path`; code None when it failed to
        answer as promised (a traceback, no line or several, an exit other than 0, 1, 2, a checker
        bug caught as 'the checker failed')."""
        def limits():
            default_stop_signals()
            if vlimit:
                import resource
                resource.setrlimit(resource.RLIMIT_AS, (vlimit, vlimit))
        try:
            p = subprocess.run(["/usr/bin/python3", os.path.join(self.scripts, "vibro_check_proof.py"), path],
                               capture_output=True, text=True, timeout=900, preexec_fn=limits)
        except subprocess.TimeoutExpired:
            return None, "ran past 900 s", ""
        lines = p.stdout.splitlines()
        line = lines[0] if lines else ""
        if p.returncode not in (0, 1, 2) or len(lines) != 1 or "Traceback" in p.stderr or \
                not line.startswith(("confirmed:", "not confirmed:", "not a certificate:")) or \
                (p.returncode, line.split(":")[0]) not in ((0, "confirmed"), (1, "not confirmed"), (2, "not a certificate")):
            return None, f"exit {p.returncode}: {p.stdout[-400:]}", p.stderr[-600:]
        if "the checker failed" in line:
            return None, line, p.stderr[-300:]
        return p.returncode, line, p.stderr

    def mutate_certificate(self, data):
        """A damaged copy of a certificate's bytes and what was done; the second value says whether
        a claim was changed (then 'confirmed' would be false)."""
        r = self.rng
        op = r.choice(["leaf", "leaf", "leaf", "shift", "shift", "shift", "delete", "add", "swap", "bytes", "dup-key",
                       "deep", "huge-list", "type"])
        if op == "bytes":
            b = bytearray(data)
            how = r.choice(["flip", "truncate", "utf8", "bom"])
            if how == "flip":
                for _ in range(r.randint(1, 8)):
                    b[r.randrange(len(b))] ^= 1 << r.randrange(8)
            elif how == "truncate":
                b = b[: r.randrange(len(b))]
            elif how == "utf8":
                k = r.randrange(len(b))
                b[k:k] = b"\xff\xfe"
            else:
                b = bytearray(b"\xef\xbb\xbf") + b
            return bytes(b), f"bytes-{how}", False
        doc = json.loads(data)
        paths = []

        def walk(o, p):
            if isinstance(o, dict):
                for k, v in o.items():
                    paths.append((p + (k,), v))
                    walk(v, p + (k,))
            elif isinstance(o, list):
                for i, v in enumerate(o[:200]):
                    paths.append((p + (i,), v))
                    walk(v, p + (i,))
        walk(doc, ())
        if not paths:
            return data, "none", False

        def parent(p):
            o = doc
            for k in p[:-1]:
                o = o[k]
            return o
        changed = False
        if op == "shift":
            # A claim moved off the truth: an interval (a string "[a, b]" or a list [a, b] of numbers)
            # moved by three times its width and more, both ends the same way (moving one end
            # outward only widens it, still true). A single number changed is judged by nothing
            # (it may be a parameter of the proof, not a claim).
            def interval(v):
                if isinstance(v, str) and re.fullmatch(r"\s*\[\s*[-+0-9.eE]+\s*,\s*[-+0-9.eE]+\s*\]\s*", v):
                    lo, hi = (float(x) for x in v.strip()[1:-1].split(","))
                    return lo, hi
                if isinstance(v, list) and len(v) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                               for x in v) and v[0] <= v[1]:
                    return float(v[0]), float(v[1])
                return None
            intervals = [(p, v) for p, v in paths if interval(v) is not None and all(map(math.isfinite, interval(v)))]
            numbers = [(p, v) for p, v in paths if isinstance(v, (int, float)) and not isinstance(v, bool)]
            if intervals and (r.random() < 0.8 or not numbers):
                p, v = r.choice(intervals)
                lo, hi = interval(v)
                d = (hi - lo) * r.choice([3, 100]) + 1e-6 * max(abs(lo), abs(hi)) + 1e-300
                d *= r.choice([1, -1])
                moved = [lo + d, hi + d]
                parent(p)[p[-1]] = f"[{moved[0]!r}, {moved[1]!r}]" if isinstance(v, str) else moved
                changed = True
            elif numbers:
                p, v = r.choice(numbers)
                parent(p)[p[-1]] = r.choice([v + 1, v * 1.001 + 1e-9, -v - 1, v * 2 + 1])
                if isinstance(v, int):
                    parent(p)[p[-1]] = int(parent(p)[p[-1]])
                changed = None
            else:
                return data, "none", False
            op += ":" + "/".join(map(str, p))
        elif op == "leaf":
            p, v = r.choice(paths)
            parent(p)[p[-1]] = r.choice([None, True, "", "x", 0, -1, 1e308, 1.7976931348623157e308, 5e-324,
                                         "[1, 0]", "[nan, 1]", "[inf, inf]", "[1e400, 2]", "[ 0 , 0 ]", "1, 2",
                                         "x" * 100000, [], {}, [0.0] * 3, {"a": 1}, 2 ** 64, -2 ** 63, 1e-320])
            op += ":" + "/".join(map(str, p))
        elif op == "type":
            p, v = r.choice(paths)
            parent(p)[p[-1]] = [v] if not isinstance(v, list) else (v[0] if v else {})
            op += ":" + "/".join(map(str, p))
        elif op == "delete":
            p, _ = r.choice(paths)
            o = parent(p)
            del o[p[-1]]
            op += ":" + "/".join(map(str, p))
        elif op == "add":
            dicts = [v for _, v in paths if isinstance(v, dict)] + [doc]
            r.choice(dicts)[r.choice(["extra", "note", "kind", "x" * 70])] = r.choice([1, "x", None, [1]])
        elif op == "swap":
            lists = [(p, v) for p, v in paths if isinstance(v, list) and len(v) > 1]
            if not lists:
                return data, "none", False
            p, v = r.choice(lists)
            i, j = r.sample(range(len(v)), 2)
            if v[i] != v[j]:
                changed = None  # a reordering may or may not change a claim
            v[i], v[j] = v[j], v[i]
            op += ":" + "/".join(map(str, p))
        elif op == "deep":
            p, _ = r.choice(paths)
            depth = r.choice([100, 5000, 50000])
            parent(p)[p[-1]] = "__DEEP__"
            op += f"({depth})"
            op += ":" + "/".join(map(str, p))
        elif op == "huge-list":
            lists = [(p, v) for p, v in paths if isinstance(v, list)]
            if not lists:
                return data, "none", False
            p, v = r.choice(lists)
            parent(p)[p[-1]] = (v * (r.choice([1000, 200000]) // max(1, len(v)) + 1))[: 200000]
            op += ":" + "/".join(map(str, p))
        text = json.dumps(doc)
        if op.startswith("deep"):
            text = text.replace('"__DEEP__"', "[" * depth + "0" + "]" * depth, 1)
        if op == "dup-key":
            k = next(iter(doc)) if isinstance(doc, dict) and doc else None
            if k is None:
                return data, "none", False
            text = "{" + json.dumps(k) + ": 1, " + text[1:]
        return text.encode(), op, changed

    def gen_checker(self):
        r = self.rng
        if not self.certificates:
            return False
        src = r.choice(self.certificates)
        data = open(src, "rb").read()
        mutated, what, changed = self.mutate_certificate(data)
        path = self.fresh(".json")
        with open(path, "wb") as f:
            f.write(mutated)
        self.runs += 1
        self.categories["checker"] = self.categories.get("checker", 0) + 1
        self.inputs.add(("checker", hashlib.sha1(mutated).hexdigest()))
        vlimit = r.choice([None, None, None, 1 << 30])
        code, line, err = self.check_certificate(path, vlimit)
        self.exits[f"checker {code}"] = self.exits.get(f"checker {code}", 0) + 1
        cmd = ["vibro_check_proof.py", path] + ([f"(ulimit -v {vlimit >> 10})"] if vlimit else [])
        if changed and src not in self.base_codes:
            self.base_codes[src] = self.check_certificate(src)[0]
        base_code = self.base_codes.get(src)
        if code is None:
            self.find("the checker did not answer in one line (0, 1 or 2)", cmd, f"[checker] {what}: {line} {err}")
        elif code == 0 and changed and base_code == 0:
            self.find("the checker confirmed a certificate with a changed claim", cmd, f"[checker] {what}: {line}")
        os.remove(path)

    def main(self, runs):
        self.seeds_()
        gens = {"from-branch": (0.22, self.gen_from_branch), "validate-input": (0.22, self.gen_validate_input),
                "score-input": (0.22, self.gen_score_input), "python-api": (0.16, self.gen_python_api),
                "two-writers": (0.09, self.gen_two_writers), "full-disk": (0.09, self.gen_full_disk),
                "prove-branch": (0.1, self.gen_prove_branch), "contacts": (0.15, self.gen_contacts),
                "sequence-column": (0.15, self.gen_sequence_column), "extend-fsize": (0.05, self.gen_extend_fsize),
                "compliant": (0.15, self.gen_compliant),
                "harmonics": (0.15, lambda: self.gen_harmonics_equivalence() if self.rng.random() < 0.2
                              else self.gen_harmonics()),
                "curve": (0.08, self.gen_curve), "prove-bifurcation": (0.08, self.gen_prove_bifurcation),
                "checker": (0.12, self.gen_checker)}
        if self.only:
            gens = {self.only: (1.0, gens[self.only][1])}
        if "checker" in gens:
            self.seed_certificates()
        total = sum(w for w, _ in gens.values())
        while self.runs < runs and self.time_left():
            x = self.rng.random() * total
            for name, (w, gen) in gens.items():
                if x < w:
                    if gen() is False:  # a surface this machine cannot reach (no tmpfs)
                        gens.pop(name)
                        total -= w
                    break
                x -= w
            if self.runs % 100 == 0:
                print(f"{self.runs} runs, {len(self.inputs)} distinct inputs, {len(self.findings)} findings",
                      flush=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("vibro")
    ap.add_argument("scenes")
    ap.add_argument("scripts")
    ap.add_argument("pythonpath")
    ap.add_argument("--runs", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--minutes", type=float, default=40)
    ap.add_argument("--report", default="")
    ap.add_argument("--only", default="", choices=[""] + CATEGORIES)
    a = ap.parse_args()
    work = tempfile.mkdtemp(prefix="vibro_surfaces_")
    c = Surfaces(os.path.abspath(a.vibro), os.path.abspath(a.scenes), os.path.abspath(a.scripts),
                 os.path.abspath(a.pythonpath), a.seed, time.monotonic() + 60 * a.minutes, work)
    c.only = a.only
    t0 = time.monotonic()
    try:
        c.main(a.runs)
    finally:
        for d in os.listdir(work):
            if d.endswith(".mnt"):
                subprocess.run(["umount", "-l", os.path.join(work, d)], capture_output=True)
        shutil.rmtree(work, ignore_errors=True)
    return write_report(c, t0, a.report, {"tmpfs": c.can_mount})


if __name__ == "__main__":
    sys.exit(main())
