#!/usr/bin/python3
"""The tables of docs/peers.md from docs/peers.csv (one run of run_all.py), in Markdown on stdout.

1. Per scene, vibro's exact engine against the most accurate run of each peer: its error, and
   its CPU as ratios to vibro's exact engine on the same scene, whole process against whole
   process (×W), call against call (×C), and the peer's call against a whole vibro process (×CW).
2. Every engine and setting (rows) on every scene (columns, in two tables): "error (×W, ×C)", or
   "gave up at t = …" / "fails: …" for a run that did not reach t_end.

Usage: /usr/bin/python3 benchmarks/peers/table.py [docs/peers.csv]
"""
import csv
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SHORT = {"fig08_preload.toml": "Fig. 8", "fig05_coexistence.toml": "Fig. 5", "fig11_clearance.toml": "Fig. 11",
         "fig04_subharmonic.toml": "Fig. 4", "chain2.toml": "chain2", "chain2_damped.toml": "chain2_damped",
         "chain3.toml": "chain3", "contacts_two_sided_1dof.toml": "two-sided 1-DOF",
         "contacts_preload_clearance_1dof.toml": "seat + lift stop", "contacts_chain2.toml": "contacts_chain2",
         "contacts_impact_pair.toml": "impact pair", "contacts_beam3.toml": "beam3 (5 contacts)"}
PEERS = ("SciPy DOP853", "Siconos Moreau–Jean")


def number(x):
    """An error as in the table: 0, or two significant digits."""
    v = float(x)
    if v == 0:
        return "0"
    m, e = f"{v:.1e}".split("e")
    return m if int(e) == 0 else f"{m}e{int(e)}"


def ratio(x):
    v = float(x)
    return f"{v:.2g}" if v < 100 else f"{v:.0f}"


def ok(r):
    return r["status"] == "ok" and r["event_error"] not in ("", "nan")


def cell(r):
    ratios = f"(×{ratio(r['whole_ratio'])}, ×{ratio(r['call_ratio'])})"
    if ok(r):
        return f"{number(r['event_error'])} {ratios}"
    s = r["status"]
    m = re.search(r"t = ([0-9.e+-]+)", s)
    if s.startswith("gave up"):
        return f"gave up at t = {float(m.group(1)):.3g} {ratios}" if m else f"gave up {ratios}"
    return f"{s[:40]} {ratios}"


def summary(rows):
    scenes = list(dict.fromkeys(r["scene_file"] for r in rows))
    head = "| scene | vibro exact: error / T, whole process, call |"
    for peer in PEERS:
        head += f" {peer}, most accurate: setting, error / T, ×W, ×C, ×CW |"
    print(head)
    print("|---" * (1 + 1 + len(PEERS)) + "|")
    for f in scenes:
        mine = [r for r in rows if r["scene_file"] == f]
        v = next(r for r in mine if r["engine"] == "vibro exact")
        line = (f"| {SHORT.get(f, f)} | {number(v['event_error'])}, {1e3 * float(v['whole_cpu_s']):.1f} ms, "
                f"{1e3 * float(v['call_cpu_s']):.2f} ms |")
        for peer in PEERS:
            runs = [r for r in mine if r["engine"] == peer and ok(r)]
            if not runs:
                line += " no run completed |"
                continue
            b = min(runs, key=lambda r: float(r["event_error"]))
            line += (f" {b['setting'].split(',')[0]}: {number(b['event_error'])}, ×{ratio(b['whole_ratio'])}, "
                     f"×{ratio(b['call_ratio'])}, ×{ratio(b['call_vs_whole'])} |")
        print(line)


def full(rows):
    scenes = list(dict.fromkeys(r["scene_file"] for r in rows))
    half = (len(scenes) + 1) // 2
    for part in (scenes[:half], scenes[half:]):
        if not part:
            continue
        order, cells = [], {}
        for r in rows:
            key = f"{r['engine']}, {r['setting']}"
            if key not in cells:
                order.append(key)
                cells[key] = {}
            cells[key][r["scene_file"]] = cell(r)
        print()
        print("| engine, setting | " + " | ".join(SHORT.get(f, f) for f in part) + " |")
        print("|---" * (len(part) + 1) + "|")
        for key in order:
            if any(f in cells[key] for f in part):
                print(f"| {key} | " + " | ".join(cells[key].get(f, "—") for f in part) + " |")


def print_tables(rows):
    summary(rows)
    full(rows)


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "peers.csv")
    with open(path) as f:
        print_tables(list(csv.DictReader(f)))


if __name__ == "__main__":
    main()
