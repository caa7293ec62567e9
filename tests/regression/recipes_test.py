#!/usr/bin/python3
"""The COCO and AUTO-07p recipes of docs/validation.md, run as documented on files in those tools'
formats, made here from a closed form (no COCO, MATLAB or AUTO needed).

    recipes_test.py ROOT VIBRO

The truth: the period-1 single-impact orbits of Fig. 5's oscillator (Ẍ + X = f sin ωt, stop at
x0 = 1, r = 0.75, ω = 10), in closed form. After an impact at t0 with velocity v+ the flight is
X(τ) = P(t0 + τ) + A cos τ + B sin τ, P(t) = f sin ωt/(1 − ω²); the orbit returns to the stop after
T = 2π/ω with X(T) = x0 and v+ = −r Ẋ(T). X(0) = x0 gives A = x0 − P(t0), X(T) = x0 gives
B = A (1 − cos T)/sin T, and the restitution law leaves one equation in t0, solved by bisection;
flights that cross the stop are discarded. Stability from the impact map's Jacobian (central
differences of this closed form; its determinant is r², a check of its own). Two families: t0 ≈ 0.11
(stable up to a flip between f = 1.2 and 1.5) and t0 ≈ 0.51 (unstable).

  * COCO: the file the documented MATLAB code writes (its fprintf formats, emulated: the post-impact
    state of the segment that starts at the impact, `ustab == 0` as the stability claim), for the
    unstable family;
  * AUTO: s.fig05 and b.fig05 as AUTO-07p writes them (fort.8's 12-integer headers and mesh rows of
    (t, U) with U = (x, ẋ, sin ωt, cos ωt) in 11-digit E format, fort.7's BR PT TY LAB rows with
    PT < 0 where stable), for the stable-then-flipped family.

The `$ ` commands of the blocks of docs/validation.md marked for this test are run in a directory
holding those files, and what they print is compared with what the page shows (docs_test.py's
rules). Then the same recipes must fail where they should: a COCO row 1e-3 off its orbit is
`no-orbit-near`, and an AUTO file with a flipped PT sign is `stability-differs`.
"""
import math
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402
from docs_test import shown_in  # noqa: E402

F, W, R, X0 = [1.0, 1.1, 1.2, 1.3, 1.4, 1.5], 10.0, 0.75, 1.0
T = 2 * math.pi / W


def flight(t0, v, f):
    """(X, Ẋ) of the flight from the post-impact state (t0, v), as functions of τ."""
    k = f / (1 - W * W)
    a = X0 - k * math.sin(W * t0)
    b = v - k * W * math.cos(W * t0)
    return (lambda s: k * math.sin(W * (t0 + s)) + a * math.cos(s) + b * math.sin(s),
            lambda s: k * W * math.cos(W * (t0 + s)) - a * math.sin(s) + b * math.cos(s))


def orbits(f):
    """[(t0, v+)] of the admissible period-1 single-impact orbits, t0 in [0, T)."""
    k = f / (1 - W * W)

    def post(t0):
        a = X0 - k * math.sin(W * t0)
        return a * (1 - math.cos(T)) / math.sin(T) + k * W * math.cos(W * t0)

    def g(t0):
        x, dx = flight(t0, post(t0), f)
        return post(t0) + R * dx(T)
    out, n = [], 4000
    for i in range(n):
        a, b = T * i / n, T * (i + 1) / n
        if g(a) * g(b) > 0:
            continue
        for _ in range(200):
            m = 0.5 * (a + b)
            a, b = (a, m) if g(a) * g(m) <= 0 else (m, b)
        t0 = 0.5 * (a + b)
        v = post(t0)
        x, _ = flight(t0, v, f)
        if v > 0 and all(x(T * j / 500) >= X0 - 1e-12 for j in range(1, 500)):
            out.append((t0, v))
    return out


def impact_map(t0, v, f):
    x, dx = flight(t0, v, f)
    s = T
    for _ in range(60):
        s -= (x(s) - X0) / dx(s)
    return t0 + s - T, -R * dx(s)


def largest_multiplier(t0, v, f, h=1e-6):
    """(max |μ|, det J) of the impact map's Jacobian by central differences."""
    cols = []
    for dt, dv in ((h, 0), (0, h)):
        a, b = impact_map(t0 + dt, v + dv, f), impact_map(t0 - dt, v - dv, f)
        cols.append(((a[0] - b[0]) / (2 * h), (a[1] - b[1]) / (2 * h)))
    j00, j10 = cols[0]
    j01, j11 = cols[1]
    tr, det = j00 + j11, j00 * j11 - j01 * j10
    disc = tr * tr / 4 - det
    mu = max(abs(tr / 2 + math.sqrt(disc)), abs(tr / 2 - math.sqrt(disc))) if disc >= 0 else math.sqrt(det)
    return mu, det


def families():
    """{'low': [(f, t0, v, stable)], 'high': [...]} over F."""
    fam = {"low": [], "high": []}
    for f in F:
        found = orbits(f)
        check(f"two admissible period-1 impact orbits at f = {f}", len(found) == 2, found)
        for (t0, v), name in zip(sorted(found), ("low", "high")):
            mu, det = largest_multiplier(t0, v, f)
            check(f"det of the impact map = r² at f = {f}, t0 = {t0:.4f}", abs(det - R * R) < 1e-6, det)
            fam[name].append((f, t0, v, mu < 1))
    return fam


def write_coco(path, rows, off=None):
    """The CSV of the MATLAB recipe: its header and '%.17g,%.17g%s%s,1,%d' rows (n = 1)."""
    with open(path, "w") as fh:
        fh.write("value,time,displacement_1,velocity_1,period,stable\n")
        for i, (f, t0, v, stable) in enumerate(rows):
            x = X0 + (1e-3 if i == off else 0.0)
            fh.write("%.17g,%.17g,%.17g,%.17g,1,%d\n" % (f, t0, x, v, 1 if stable else 0))


def e(x):
    return "%19.10E" % x


def write_auto(s_path, b_path, rows, flip=None, ntpl=6):
    """s.NAME and b.NAME of a branch continued in PAR(1) = f, with PAR(2) = ω, PAR(11) = T."""
    ndim, nparx = 4, 36
    with open(s_path, "w") as s, open(b_path, "w") as b:
        b.write("   0    PT  TY  LAB    PAR(1)        L2-NORM         U(1)             U(2)\n")
        for i, (f, t0, v, stable) in enumerate(rows):
            lab, pt = i + 1, 10 * (i + 1)
            if stable != (i == flip):
                pt = -pt
            x, dx = flight(t0, v, f)
            mesh = []
            for j in range(ntpl):
                tau = T * j / (ntpl - 1)
                mesh.append([j / (ntpl - 1), x(tau), dx(tau), math.sin(W * (t0 + tau)), math.cos(W * (t0 + tau))])
            nrowpr = ntpl * 1 + 1 + 1 + ntpl * 1 + math.ceil(nparx / 7)
            s.write("%6d%6d%6d%6d%6d%6d%8d%6d%8d%5d%5d%5d\n"
                    % (1, pt, 4, lab, 1, 1, ntpl, ndim + 1, nrowpr, ntpl - 1, 4, nparx))
            for row in mesh:
                s.write("    " + "".join(e(u) for u in row) + "\n")
            s.write("%6d\n" % 1)                               # ICP(1) = 1: f is continued
            s.write("    " + e(1.0) + "\n")                    # its derivative
            for row in mesh:
                s.write("    " + "".join(e(0.0) for _ in row[1:]) + "\n")   # U̇
            par = [0.0] * nparx
            par[0], par[1], par[10] = f, W, T
            for k in range(0, nparx, 7):
                s.write("    " + "".join(e(p) for p in par[k:k + 7]) + "\n")
            norm = math.sqrt(sum(u * u for r_ in mesh for u in r_[1:]) / ntpl)
            b.write("%4d%6d%4d%5d" % (1, pt, 4, lab) + e(f) + e(norm) + e(x(0.0)) + e(dx(0.0)) + "\n")


def documented_blocks(page):
    """[(line, [(command, shown lines)])] of the blocks marked for this test."""
    with open(page, encoding="utf-8") as fh:
        lines = fh.read().splitlines()
    out = []
    for i, line in enumerate(lines):
        if not re.match(r"^<!-- docs-output: skip .*recipes_test\.py.* -->$", line):
            continue
        k = i + 1
        while not lines[k].strip():
            k += 1
        assert lines[k].startswith("```"), (page, k)
        body, k = [], k + 1
        while not lines[k].startswith("```"):
            body.append(lines[k])
            k += 1
        steps, j = [], 0
        while j < len(body):
            cmd = body[j][2:]
            while cmd.endswith("\\"):
                j += 1
                cmd = cmd[:-1] + " " + body[j].strip()
            j += 1
            shown = []
            while j < len(body) and not body[j].startswith("$ "):
                shown.append(body[j])
                j += 1
            steps.append((cmd, shown))
        out.append((i + 2, steps))
    return out


def run(cmd, work, env):
    p = subprocess.run(["bash", "-c", cmd], cwd=work, env=env, capture_output=True, text=True, timeout=600)
    return p.returncode, (p.stdout + p.stderr).splitlines()


def main():
    root, vibro = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    fam = families()
    check("the low family is stable at f = 1 and has flipped by f = 1.5",
          fam["low"][0][3] and not fam["low"][-1][3], fam["low"])
    check("the high family is unstable", not any(r[3] for r in fam["high"]), fam["high"])
    page = os.path.join(root, "docs", "validation.md")
    blocks = documented_blocks(page)
    check("docs/validation.md has the COCO and the AUTO blocks for this test", len(blocks) == 2, blocks)
    with tempfile.TemporaryDirectory() as work:
        for name in ("data", "scripts"):
            os.symlink(os.path.join(root, name), os.path.join(work, name))
        os.mkdir(os.path.join(work, "bin"))
        os.symlink(vibro, os.path.join(work, "bin", "vibro"))
        env = dict(os.environ, PATH=os.path.join(work, "bin") + os.pathsep + os.environ.get("PATH", ""))
        write_coco(os.path.join(work, "coco_branch.csv"), fam["high"])
        write_auto(os.path.join(work, "s.fig05"), os.path.join(work, "b.fig05"), fam["low"])
        commands = 0
        for line, steps in blocks:
            rc = 0
            for cmd, shown in steps:
                if cmd.strip() == "echo $?":
                    printed = [str(rc)]
                else:
                    rc, printed = run(cmd, work, env)
                commands += 1
                missing = shown_in(shown, printed)
                check(f"validation.md:{line}: `{cmd}` prints what the page shows", missing is None,
                      f"shown but not printed: {missing!r}\nprinted:\n" + "\n".join(printed))
        check("every documented recipe command ran (1 COCO, 2 AUTO)", commands == 3, commands)
        # Every orbit of both files confirmed, with the closed form's stability.
        for csv_name, n in (("coco_branch.csv", len(fam["high"])), ("auto_branch.csv", len(fam["low"]))):
            rc, printed = run(f"vibro validate data/scenes/fig05_coexistence.toml {csv_name} "
                              "--param excitation.amplitude", work, env)
            check(f"{csv_name}: all {n} closed-form orbits confirmed", rc == 0 and
                  printed[-1] == f"{n} of {n} points confirmed", "\n".join(printed))
        # The recipes can fail: a state 1e-3 off its orbit, a stability mark of AUTO flipped.
        write_coco(os.path.join(work, "coco_off.csv"), fam["high"], off=2)
        rc, printed = run("vibro validate data/scenes/fig05_coexistence.toml coco_off.csv "
                          "--param excitation.amplitude", work, env)
        check("COCO row 2 moved 1e-3 off its orbit: exit 4, no-orbit-near", rc == 4 and
              sum("no-orbit-near" in p for p in printed) == 1, "\n".join(printed))
        write_auto(os.path.join(work, "s.flip"), os.path.join(work, "b.flip"), fam["low"], flip=0)
        rc, printed = run("scripts/auto_to_csv.py s.flip --b b.flip --dofs 1 --sin 3 --omega 10 flip.csv && "
                          "vibro validate data/scenes/fig05_coexistence.toml flip.csv --param excitation.amplitude",
                          work, env)
        check("AUTO's PT sign flipped at LAB 1: exit 4, stability-differs", rc == 4 and
              sum("stability-differs" in p for p in printed) == 1, "\n".join(printed))
        # Bad files: exit 2 naming the file and the line.
        with open(os.path.join(work, "s.bad"), "w") as fh:
            fh.write(open(os.path.join(work, "s.fig05")).read().replace("E+00", "X+00", 1))
        rc, printed = run("scripts/auto_to_csv.py s.bad --dofs 1 --sin 3 --omega 10", work, env)
        check("a malformed s. file: exit 2 naming s.bad and its line", rc == 2 and
              any(re.search(r"s\.bad:\d+: '", p) for p in printed), "\n".join(printed))
    finish()


if __name__ == "__main__":
    main()
