#!/usr/bin/python3
"""A branch of periodic orbits from AUTO-07p's files as the CSV `vibro validate` reads, without
AUTO itself.

    scripts/auto_to_csv.py s.NAME --dofs N --sin K (--omega W | --omega-par J) [options] [OUT.csv]
    vibro-auto-to-csv ...     (installed by `cmake --install`)

The forced system is taken as AUTO models one: autonomised with an oscillator pair,
U = (q_1..q_N, q̇_1..q̇_N, ..., sin ωt at U(K), cos ωt at U(K+1), ...). From each labelled solution
of s.NAME (fort.8) it takes the first mesh point: the displacements U(1..N), the velocities
U(N+1..2N) (in the scene's [initial] convention) and the time atan2(U(K), U(K+1))/ω in [0, T).

Options:
  --dofs N        displacements and velocities per state
  --sin K         1-based index of sin ωt in U (cos ωt is U(K+1))
  --omega W       the forcing frequency, or
  --omega-par J   ... read from PAR(J) of each solution (when ω is the continued parameter)
  --par I         the column `value` is PAR(I) (default: the first free parameter, ICP(1))
  --b b.NAME      the branch file (fort.7): `stable` is 1 where the solution's point number PT
                  is negative (AUTO's mark of a stable periodic orbit), 0 elsewhere
Without OUT.csv the CSV goes to stdout. `period` is PAR(11)·ω/2π, AUTO's period in forcing
periods, when it is within 1e-6 of a whole number (else empty). Exit 2 on a malformed file,
naming it and the line.

The s. file: per solution a header of 12 integers (IBR NTOT ITP LAB NFPR ISW NTPL NAR NROWPR NTST
NCOL NPARX), then NTPL rows of (t, U(1..NAR−1)), the NFPR free parameter indices ICP, their
NFPR derivatives, NTPL rows of U̇ (NAR−1 each), and PAR(1..NPARX); numbers are read in order,
whatever the line breaks.
"""
import argparse
import csv
import math
import sys


class Malformed(Exception):
    pass


def tokens(path):
    """(line number, token) of every number-like token of a text file."""
    with open(path, encoding="ascii", errors="replace") as f:
        for n, line in enumerate(f, 1):
            for t in line.split():
                yield n, t


def number(tok, path, line):
    try:
        return float(tok.replace("D", "E").replace("d", "e"))
    except ValueError:
        raise Malformed(f"{path}:{line}: '{tok}' is not a number") from None


def integer(tok, path, line):
    try:
        return int(tok)
    except ValueError:
        raise Malformed(f"{path}:{line}: '{tok}' is not an integer") from None


def solutions(path):
    """Each labelled solution of an s. file: dict(lab, line, icp, u0 = first mesh row's U, par)."""
    it = tokens(path)
    out = []
    while True:
        head = []
        for n, t in it:
            head.append((n, t))
            if len(head) == 12:
                break
        if not head:
            return out
        if len(head) < 12:
            raise Malformed(f"{path}:{head[0][0]}: a solution header needs 12 integers, the file ends after {len(head)}")
        line = head[0][0]
        ibr, ntot, itp, lab, nfpr, isw, ntpl, nar, nrowpr, ntst, ncol, nparx = (
            integer(t, path, n) for n, t in head)
        if ntpl < 1 or nar < 2 or nfpr < 1 or nparx < 1:
            raise Malformed(f"{path}:{line}: header NTPL {ntpl}, NAR {nar}, NFPR {nfpr}, NPARX {nparx}: "
                            "expected NTPL ≥ 1, NAR ≥ 2, NFPR ≥ 1, NPARX ≥ 1")

        def take(k, what):
            vals = []
            for n, t in it:
                vals.append((n, t))
                if len(vals) == k:
                    return vals
            raise Malformed(f"{path}: solution LAB {lab} (line {line}) ends in its {what}")
        def numbers(k, what):  # every number is read, so that a damaged one is reported
            return [number(t, path, n) for n, t in take(k, what)]
        rows = numbers(ntpl * nar, "mesh rows (t, U)")
        u0 = rows[1:nar]
        icp = [integer(t, path, n) for n, t in take(nfpr, "free parameter indices")]
        numbers(nfpr, "parameter derivatives")
        numbers(ntpl * (nar - 1), "derivative rows")
        par = numbers(nparx, "parameters")
        out.append({"lab": lab, "line": line, "icp": icp, "u0": u0, "par": par})


def stability(path):
    """LAB → 1 (PT < 0, stable) or 0, from the labelled rows of a b. file."""
    labs = {}
    with open(path, encoding="ascii", errors="replace") as f:
        for n, line in enumerate(f, 1):
            w = line.split()
            if len(w) < 4 or w[0] == "0":
                continue  # blank, or a header/comment row (BR = 0)
            br, pt, ty, lab = (integer(t, path, n) for t, _ in zip(w, range(4)))
            if lab != 0:
                labs[lab] = 1 if pt < 0 else 0
    return labs


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], add_help=True)
    ap.add_argument("s_file")
    ap.add_argument("out", nargs="?")
    ap.add_argument("--dofs", type=int, required=True)
    ap.add_argument("--sin", type=int, required=True)
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--omega", type=float)
    g.add_argument("--omega-par", type=int)
    ap.add_argument("--par", type=int)
    ap.add_argument("--b", dest="b_file")
    a = ap.parse_intermixed_args(argv[1:])
    n = a.dofs
    try:
        sols = solutions(a.s_file)
        stable = stability(a.b_file) if a.b_file else {}
    except OSError as e:
        print(f"auto_to_csv: {e}", file=sys.stderr)
        return 2
    except Malformed as e:
        print(f"auto_to_csv: {e}", file=sys.stderr)
        return 2
    rows = []
    for s in sols:
        u, par = s["u0"], s["par"]
        where = f"{a.s_file}:{s['line']}: solution LAB {s['lab']}"
        if a.sin + 1 > len(u) or 2 * n > len(u) or n < 1 or a.sin < 1:
            print(f"auto_to_csv: {where} has {len(u)} components; --dofs {n} and --sin {a.sin} need "
                  f"{max(2 * n, a.sin + 1)}", file=sys.stderr)
            return 2
        p = a.par if a.par is not None else s["icp"][0]
        for k, what in ((p, "--par"), (a.omega_par, "--omega-par")):
            if k is not None and not 1 <= k <= len(par):
                print(f"auto_to_csv: {where}: {what} {k} is beyond its {len(par)} parameters", file=sys.stderr)
                return 2
        w = a.omega if a.omega is not None else par[a.omega_par - 1]
        if not (math.isfinite(w) and w > 0):
            print(f"auto_to_csv: {where}: ω = {w!r}: expected a finite positive frequency", file=sys.stderr)
            return 2
        phase = math.atan2(u[a.sin - 1], u[a.sin]) % (2 * math.pi)
        q = par[10] * w / (2 * math.pi) if len(par) >= 11 else float("nan")
        period = str(round(q)) if math.isfinite(q) and round(q) >= 1 and abs(q - round(q)) <= 1e-6 * q else ""
        claim = stable.get(s["lab"])
        rows.append([repr(par[p - 1]), repr(phase / w)] + [repr(x) for x in u[:2 * n]]
                    + [period, "" if claim is None else claim])
    out = open(a.out, "w", newline="") if a.out else sys.stdout
    wr = csv.writer(out, lineterminator="\n")
    wr.writerow(["value", "time"] + [f"displacement_{i + 1}" for i in range(n)]
                + [f"velocity_{i + 1}" for i in range(n)] + ["period", "stable"])
    wr.writerows(rows)
    if out is not sys.stdout:
        out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
