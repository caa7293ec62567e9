#!/usr/bin/python3
"""The table of docs/peers.md from docs/peers.csv (one run of run_all.py), in Markdown on stdout:
one row per engine and setting, one column per scene, each cell
"stick/release time error / T (×A, ×B)", where A is the CPU time ÷ that of a whole process of
vibro's exact engine on the same scene (start-up included) and B the CPU time ÷ that engine's work
alone (start-up excluded, as the peers' times exclude their interpreter's), or
"gave up at t = …" / "fails at t = …" for runs that did not reach t_end, "—" where the setting
does not apply.

Usage: /usr/bin/python3 benchmarks/peers/table.py [docs/peers.csv]
"""
import csv
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
COLUMNS = [("fig08_preload.toml", "Fig. 8"), ("fig05_coexistence.toml", "Fig. 5"),
           ("fig11_clearance.toml", "Fig. 11"), ("fig04_subharmonic.toml", "Fig. 4"),
           ("chain2.toml", "chain2"), ("chain2_damped.toml", "chain2_damped"), ("chain3.toml", "chain3")]


def label(engine, setting):
    """Row label, shortened as in docs/peers.md."""
    m = re.match(r"DOP853 rtol (\S+), plastic below (\S+)", setting)
    if engine == "SciPy restart" and m:
        return f"SciPy, DOP853 rtol {float(m.group(1)):g} + plastic < {m.group(2)}"
    if engine == "SciPy naive":
        return "SciPy, rtol 1e-9, impact by impact"
    m = re.match(r"theta 0.5, (h = T/\d+)", setting)
    if engine == "Siconos Moreau–Jean" and m:
        return f"Siconos Moreau–Jean, {m.group(1)}"
    if engine == "Siconos event-driven":
        h = re.search(r"h = T/\d+", setting).group(0)
        if "default" in setting:
            return f"Siconos event-driven, LSODAR default tol. (10ε), {h}"
        rtol = re.search(r"rtol = atol = (\S+),", setting).group(1)
        return f"Siconos event-driven, rtol {rtol}, {h}"
    m = re.match(r"Adams rtol (\S+)", setting)
    if engine == "vibro CVODE" and m:
        return f"vibro CVODE, Adams rtol {float(m.group(1)):g}"
    return f"{engine}, {setting}"


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


def ratios(r):
    """(×A, ×B); only ×A for a CSV from before cpu_ratio_work."""
    if r.get("cpu_ratio_work"):
        return f"(×{ratio(r['cpu_ratio'])}, ×{ratio(r['cpu_ratio_work'])})"
    return f"(×{ratio(r['cpu_ratio'])})"


def cell(r):
    s = r["status"]
    if s == "ok":
        return f"{number(r['event_error'])} {ratios(r)}"
    m = re.search(r"t = ([0-9.e+-]+)", s)
    t = f"{float(m.group(1)):.3g}" if m else "?"
    what = "gave up" if s.startswith("gave up") else "fails"
    return f"{what} at t = {t} {ratios(r)}"


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs", "peers.csv")
    with open(path) as f:
        rows = list(csv.DictReader(f))
    order, cells = [], {}
    for r in rows:
        key = label(r["engine"], r["setting"])
        if key not in cells:
            order.append(key)
            cells[key] = {}
        cells[key][r["scene_file"]] = cell(r)
    print("| engine, setting | " + " | ".join(c for _, c in COLUMNS) + " |")
    print("|---" * (len(COLUMNS) + 1) + "|")
    for key in order:
        print(f"| {key} | " + " | ".join(cells[key].get(f, "—") for f, _ in COLUMNS) + " |")


if __name__ == "__main__":
    main()
