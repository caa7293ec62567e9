#!/usr/bin/python3
"""vibro against the reference on the seeded random scenes (docs/contacts_reference.md).

    sweep.py OUTDIR --vibro build/vibro [--precision quad] [--count 240] [--seed 1]
             [--first 0] [--last 240] [--timeout 120]

Writes the scenes (random_scenes.py), runs reference.py on each (OUTDIR/random_NNN.csv, reused
when present), runs `vibro simulate` on each, compares every event within 1e-10 T (compare.py)
and prints one line per scene: OK, MISMATCH (with the first divergence and vibro's status and
message), REF-UNDETERMINED (the reference does not decide the scene: a corner collapse), or
VIBRO-EXIT / VIBRO-TIMEOUT; then the counts.
"""
import argparse
import collections
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import compare  # noqa: E402
import random_scenes  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("outdir")
    ap.add_argument("--vibro", required=True)
    ap.add_argument("--precision", default="quad", choices=["double", "quad"])
    ap.add_argument("--count", type=int, default=240)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--last", type=int, default=None)
    ap.add_argument("--timeout", type=float, default=120)
    args = ap.parse_args(argv)
    random_scenes.main([args.outdir, "--count", str(args.count), "--seed", str(args.seed)])
    counts = collections.Counter()
    for i in range(args.first, args.last if args.last is not None else args.count):
        scene = os.path.join(args.outdir, f"random_{i:03d}.toml")
        ref_csv = scene.replace(".toml", ".csv")
        name = os.path.basename(scene)[:-5]
        if not os.path.exists(ref_csv):
            p = subprocess.run([sys.executable, os.path.join(HERE, "reference.py"), scene, "--out", ref_csv],
                               capture_output=True, text=True)
            if p.returncode != 0:
                if os.path.exists(ref_csv):
                    os.remove(ref_csv)
                verdict = "REF-UNDETERMINED" if p.returncode == 3 else f"REF-EXIT {p.returncode}"
                print(name, verdict, p.stderr.strip().splitlines()[-1][:200])
                counts[verdict.split()[0]] += 1
                continue
        h5 = scene.replace(".toml", f"_{args.precision}.h5")
        try:
            p = subprocess.run([args.vibro, "simulate", scene, "--out", h5, "--force",
                                "--set", f'run.precision="{args.precision}"'],
                               capture_output=True, text=True, timeout=args.timeout)
        except subprocess.TimeoutExpired:
            print(name, f"VIBRO-TIMEOUT {args.timeout:g} s")
            counts["VIBRO-TIMEOUT"] += 1
            continue
        if not os.path.exists(h5):
            print(name, "VIBRO-EXIT", p.returncode, p.stderr.strip()[:200])
            counts["VIBRO-EXIT"] += 1
            continue
        import h5py
        with h5py.File(h5, "r") as f:
            message = f.attrs.get("message", "")
        events, T, status = compare.read_h5(h5)
        res = compare.compare(compare.read_csv(ref_csv), events, T, 1e-10)
        if res.ok:
            print(name, "OK", status, res.matched, f"{res.max_dt:.2g}")
            counts["OK"] += 1
        else:
            print(name, "MISMATCH", status, message[:150], "|", res.message[:250])
            counts["MISMATCH"] += 1
    print(dict(counts))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
