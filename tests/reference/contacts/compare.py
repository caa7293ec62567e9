#!/usr/bin/python3
"""Compares an event list (vibro's HDF5 /events, or a CSV of reference.py) with a reference CSV
of reference.py, event by event, every time within `tol` forcing periods.

Matching rules (docs/contacts_reference.md, "Comparing event lists"):
* events are matched in order; events less than tol*T apart may appear in either order (an
  accumulation and its stick, two contacts at one instant);
* kind and contact must agree; impacts also compare the gap velocities before and after
  (|dv| <= vtol (1 + |v|));
* chattering: the two solvers follow a different number of explicit impacts before predicting the
  accumulation point. Where one list has an accumulation of contact k and the other still has an
  impact of k at or before that time, the extra impact is skipped (counted); the accumulation
  times themselves are compared like every other event;
* reference kinds that vibro's HDF5 enum has no name for (leave, liftoff: a held contact leaving
  without its reaction crossing zero) match a `release` of the same contact at the same time, and
  are otherwise skipped and counted.

Usage:
  compare.py SCENE.toml --ref REF.csv --vibro build/vibro     (runs `vibro simulate SCENE --out`)
  compare.py --ref REF.csv --events OTHER.csv|RUN.h5 --period T
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

VIBRO_KINDS = ("impact", "accumulation", "stick", "release", "grazing")


class Event:
    __slots__ = ("t", "kind", "contact", "vb", "va")

    def __init__(self, t, kind, contact, vb, va):
        self.t, self.kind, self.contact, self.vb, self.va = t, kind, contact, vb, va

    def __repr__(self):
        return f"{self.kind}@{self.contact} t={self.t!r} v=({self.vb:.6g}, {self.va:.6g})"


def read_csv(path):
    import csv
    with open(path) as fh:
        return [Event(float(r["t"]), r["kind"], int(r["contact"]), float(r["v_before"]), float(r["v_after"]))
                for r in csv.DictReader(fh)]


def read_h5(path):
    """vibro's /events: t, kind (HDF5 enum), v_before, v_after and, with several contacts,
    /events/contact (absent: every event is on contact 0, the [stop])."""
    import h5py
    with h5py.File(path, "r") as f:
        ev = f["events"]
        names = {v: k for k, v in h5py.check_enum_dtype(ev["kind"].dtype).items()}
        t = ev["t"][:]
        kind = ev["kind"][:]
        vb, va = ev["v_before"][:], ev["v_after"][:]
        contact = ev["contact"][:] if "contact" in ev else [0] * len(t)
        period = float(f.attrs["forcing_period"])
        status = f.attrs.get("status", "")
    return [Event(float(t[i]), names[int(kind[i])], int(contact[i]), float(vb[i]), float(va[i]))
            for i in range(len(t))], period, status


class Result:
    def __init__(self):
        self.ok = True
        self.matched = 0
        self.max_dt = 0.0          # largest time difference / T over matched events
        self.max_dv = 0.0          # largest relative velocity difference over matched impacts
        self.skipped_ref = 0       # explicit chattering impacts of the reference beyond the other's
        self.skipped_other = 0
        self.skipped_kinds = 0     # reference events of kinds vibro does not report
        self.dts = []              # |dt|/T of every matched event, in order
        self.message = ""

    def __str__(self):
        s = (f"{'OK' if self.ok else 'MISMATCH'}: {self.matched} events matched, max |dt|/T = {self.max_dt:.3g}, "
             f"max |dv|/(1+|v|) = {self.max_dv:.3g}; chattering impacts followed only by the reference: "
             f"{self.skipped_ref}, only by the other: {self.skipped_other}; reference events of kinds "
             f"without a vibro name: {self.skipped_kinds}")
        return s + ("" if self.ok else "\n" + self.message)


def compare(ref, other, T, tol=1e-10, vtol=1e-7, lookahead=4):
    """ref, other: lists of Event in time order. Returns a Result."""
    res = Result()
    i = j = 0
    while i < len(ref) and j < len(other):
        r = ref[i]
        o = other[j]
        # a held contact leaving without crossing its reaction (liftoff, leave): vibro's enum has
        # no name for it; a release of the same contact at the same time matches it, else skip it
        if r.kind not in VIBRO_KINDS:
            if o.kind == "release" and o.contact == r.contact and abs(o.t - r.t) <= tol * T:
                res.matched += 1
                res.max_dt = max(res.max_dt, abs(o.t - r.t) / T)
                res.dts.append(abs(o.t - r.t) / T)
                i += 1
                j += 1
            else:
                res.skipped_kinds += 1
                i += 1
            continue
        # one solver followed more chattering impacts before its accumulation point
        if r.kind == "impact" and o.kind == "accumulation" and r.contact == o.contact and r.t <= o.t + tol * T:
            res.skipped_ref += 1
            i += 1
            continue
        if o.kind == "impact" and r.kind == "accumulation" and r.contact == o.contact and o.t <= r.t + tol * T:
            res.skipped_other += 1
            j += 1
            continue
        # the matching event of `other`: same kind and contact within tol*T, allowing a few
        # events at (almost) the same instant to come in another order
        hit = None
        for jj in range(j, min(j + lookahead, len(other))):
            o = other[jj]
            if abs(o.t - r.t) > tol * T:
                break
            if o.kind == r.kind and o.contact == r.contact and abs(o.t - r.t) <= tol * T:
                hit = jj
                break
        if hit is not None:
            o = other[hit]
            if hit != j:                       # swap the equal-time events into place
                other = other[:j] + [o] + other[j:hit] + other[hit + 1:]
            res.matched += 1
            res.max_dt = max(res.max_dt, abs(o.t - r.t) / T)
            res.dts.append(abs(o.t - r.t) / T)
            if r.kind == "impact":
                dv = max(abs(o.vb - r.vb) / (1 + abs(r.vb)), abs(o.va - r.va) / (1 + abs(r.va)))
                res.max_dv = max(res.max_dv, dv)
                if dv > vtol:
                    res.ok = False
                    res.message = f"event {i}: velocities differ by {dv:.3g}: reference {r}, other {o}"
                    return res
            i += 1
            j += 1
            continue
        res.ok = False
        res.message = (f"first divergence at reference event {i}, other event {j}: reference {r}, other {o} "
                       f"(|dt|/T = {abs(o.t - r.t) / T:.3g})")
        return res
    if i < len(ref) or j < len(other):
        res.ok = False
        rest = ref[i:i + 3] if i < len(ref) else other[j:j + 3]
        res.message = (f"the lists end differently: {len(ref) - i} reference and {len(other) - j} other "
                       f"events left, next: {rest}")
    return res


def run_vibro(vibro, scene, workdir):
    out = os.path.join(workdir, os.path.basename(scene).replace(".toml", ".h5"))
    p = subprocess.run([vibro, "simulate", scene, "--out", out, "--force"], capture_output=True, text=True,
                       timeout=1800)
    if p.returncode != 0:
        raise RuntimeError(f"vibro simulate {scene} exited {p.returncode}: {p.stderr.strip()}")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("scene", nargs="?")
    ap.add_argument("--ref", required=True, help="reference CSV (reference.py)")
    ap.add_argument("--vibro", help="the vibro program: runs `vibro simulate SCENE --out`")
    ap.add_argument("--events", help="an event list to compare instead: CSV or vibro HDF5")
    ap.add_argument("--period", type=float, help="forcing period T (with a CSV --events)")
    ap.add_argument("--tol", type=float, default=1e-10, help="time tolerance, in forcing periods")
    args = ap.parse_args(argv)
    ref = read_csv(args.ref)
    if args.events and args.events.endswith(".csv"):
        other, T = read_csv(args.events), args.period
    else:
        path = args.events
        if path is None:
            path = run_vibro(args.vibro, args.scene, tempfile.mkdtemp(prefix="contacts_"))
        other, T, status = read_h5(path)
        print(f"vibro status: {status}")
    res = compare(ref, other, T, args.tol)
    print(res)
    return 0 if res.ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
