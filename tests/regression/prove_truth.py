"""Independent truths for the prover's tests (docs/prove.md): for the model a certificate states (its
exact decimals: modal damping and several contacts included), Newton at 50 digits on the orbit's
multiple-shooting map, with the modal flight written here in its standard form
    X_i(t) = U_i(t) + e^{-σ_i s}(a_i cos ω_d,i s + b_i sin ω_d,i s),   U_i = P_i sin ωt + Q_i cos ωt,
each impact at its contact j with the law V⁺ = V⁻ − (1 + r_j)(c_j·V⁻/W_jj) T_j; the Floquet multipliers
as the eigenvalues of the stroboscopic map's Jacobian by central differences (h = 1e-20: error
~1e-30), each impact located by a root finder at 50 digits; the determinant of that Jacobian against
its closed form Π r_j² · e^{-qT Σ 2σ_i} (docs/model.md §5.6). Nothing here reads vibro's sources.
"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

from mpmath import mp, iv, mpf, sin, cos, exp, sqrt, pi, eig, matrix

mp.dps = 50


def inside(x, pair):
    return mpf(pair[0]) <= x <= mpf(pair[1])


class Harness:
    """What every prove test does the same way: record checks, run `vibro prove SCENE --json`, run the
    checker on a file or a document, write a scene into the test's temporary directory.
    `verbose` prints every check (ok/FAIL), not only the failures."""

    def __init__(self, vibro, checker, prefix, verbose=False):
        self.vibro, self.checker, self.verbose = vibro, checker, verbose
        self.tmp = tempfile.mkdtemp(prefix=prefix)
        self.failures, self.passed = [], []
        self.checker_module = None

    def expect(self, cond, what):
        self.passed.append(what)
        if self.verbose:
            print(("ok    " if cond else "FAIL  ") + what, flush=True)
        elif not cond:
            print("FAIL:", what, flush=True)
        if not cond:
            self.failures.append(what)

    def prove(self, scene, *args, out=None):
        """(exit code, the JSON summary or None, stderr)."""
        cmd = [self.vibro, "prove", scene, "--json", *args] + (["--out", out] if out else [])
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        return p.returncode, (json.loads(p.stdout) if p.stdout.strip() else None), p.stderr

    def check(self, path):
        """The checker on a certificate file: (exit code, its JSON verdict or None)."""
        p = subprocess.run([sys.executable, self.checker, path, "--json"], capture_output=True, text=True, timeout=900)
        return p.returncode, (json.loads(p.stdout) if p.stdout.strip() else None)

    def check_doc(self, doc):
        """The checker on a certificate held in memory (an edit), in this process: its check_document
        on the bytes the command would read, with the verdict the command's --json prints. The
        checker works in mpmath's global contexts at its own precision (PREC, set when it is
        loaded); each call runs at that precision and gives this process its own back. `check` runs
        the command on a file (one line, the exit code)."""
        if self.checker_module is None:
            saved = mp.prec, iv.prec
            try:
                spec = importlib.util.spec_from_file_location("vibro_check_proof_in_process", self.checker)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
            finally:
                mp.prec, iv.prec = saved
            sys.setrecursionlimit(max(sys.getrecursionlimit(), 10000))  # as the command sets it
            self.checker_module = module
        saved = mp.prec, iv.prec
        try:
            mp.prec = iv.prec = self.checker_module.PREC
            code, line = self.checker_module.check_document(json.dumps(doc).encode())
        finally:
            mp.prec, iv.prec = saved
        if "\n" in line:
            self.expect(False, f"the checker answers in one line: {line[:300]!r}")
        verdict = line.split(":", 1)[0]
        return code, {"verdict": verdict, "reason": line.split(": ", 1)[1] if ": " in line else line}

    def scene_file(self, name, text):
        path = os.path.join(self.tmp, name)
        with open(path, "w") as fh:
            fh.write(text)
        return path

    def finish(self):
        """The closing line and the exit status."""
        print(f"{len(self.passed) - len(self.failures)}/{len(self.passed)} checks passed")
        sys.exit(1 if self.failures else 0)


def bifurcation_reading_mutations(cert):
    """Edits of a bifurcation certificate (pitchfork, fold, grazing, or a symmetric orbit's pitchfork)
    that the checker must reject (exit 1 or 2), each a hole of the checker before issue 38: the
    summary read whole (an unknown key, every key it never read deleted or of the wrong type), the
    claims it never checked (the kind of point, the parameter's key, the centre and width of the
    interval, the modal data, an orbit's events, sequence, section, multipliers or stability that
    no bifurcation proof makes, the period, the reason's sentence and the derivative's interval in
    it), lists of two grown to three or given as objects, the prover's window and the grazing's
    unknowns of the wrong type. Returns [(what, edited copy)]."""
    import copy
    out = []
    b, s = cert["bifurcation"], cert["summary"]
    kind = b["type"]

    def edit(what, f):
        c = copy.deepcopy(cert)
        f(c)
        out.append((what, c))

    def both(key, value):
        return lambda c: [c.__setitem__(key, value), c["summary"].__setitem__(key, value)]

    edit("summary: an unknown key", lambda c: c["summary"].__setitem__("note", 1))
    wrong = {"bifurcation": 5, "width": "x", "box_width": "x", "center": None, "located": "x", "param": 5,
             "stability": 1, "events": {}, "sequence": "x", "section": 5, "multipliers": {}, "modal_data": 1}
    for key, value in wrong.items():
        edit(f"summary.{key} deleted", lambda c, key=key: c["summary"].pop(key))
        edit(f"summary.{key} of the wrong type", lambda c, key=key, value=value: c["summary"].__setitem__(key, value))
    other = {"pitchfork": "fold", "fold": "pitchfork", "grazing": "pitchfork", "orbit-pitchfork": "grazing"}[kind]
    edit(f"summary.bifurcation '{other}'", lambda c: c["summary"].__setitem__("bifurcation", other))
    edit("summary.stability 'stable'", lambda c: c["summary"].__setitem__("stability", "stable"))
    edit("summary.multipliers claimed", lambda c: c["summary"].__setitem__(
        "multipliers", [{"re": [-1.0, -1.0], "im": [0.0, 0.0]}]))
    edit("summary.sequence claimed", lambda c: c["summary"].__setitem__("sequence", ["impact"]))
    edit("summary.events claimed", lambda c: c["summary"].__setitem__("events", [
        {"kind": "impact", "contact": 0, "time": [0.0, 1.0], "phase": [0.0, 1.0], "velocity_before": [-1.0, 0.0]}]))
    edit("summary.section claimed", lambda c: c["summary"].__setitem__("section", {"time": [0.0, 1.0]}))
    edit("summary.width doubled", lambda c: c["summary"].__setitem__("width", 2 * s["width"]))
    edit("summary.box_width halved", lambda c: c["summary"].__setitem__("box_width", s["box_width"] / 2))
    edit("summary.center outside the interval", lambda c: c["summary"].__setitem__(
        "center", float(s["interval"][1]) + 1e-6))
    edit("summary.param another key", lambda c: c["summary"].__setitem__(
        "param", "excitation.frequency" if s["parameter"] == "amplitude" else "excitation.amplitude"))
    edit("summary.modal_data the other one", lambda c: c["summary"].__setitem__(
        "modal_data", "given" if s["modal_data"] == "enclosed" else "enclosed"))
    edit("the period 2", both("period", 2))
    edit("the reason says at least one", both("reason", cert["reason"].replace("exactly one", "at least one", 1)))
    # The derivative's interval in the reason moved off the truth by its width and more.
    import re
    g = re.search(r"\[(-?[0-9.e+-]+), (-?[0-9.e+-]+)\]", cert["reason"][cert["reason"].index("]") + 1:])
    if g:
        a, z = float(g.group(1)), float(g.group(2))
        d = 3 * (z - a) + 1e-9 * abs(z)
        moved = cert["reason"].replace(g.group(0), f"[{a + d!r}, {z + d!r}]")
        edit("the reason's derivative moved", both("reason", moved))
    if kind in ("pitchfork", "fold"):
        edit("bifurcation.window of the wrong type", lambda c: c["bifurcation"].__setitem__("window", "x"))
        edit("bifurcation.window negative", lambda c: c["bifurcation"].__setitem__("window", -1.0))
        for where in ("bifurcation", "summary"):
            edit(f"{where}.g_at_ends grown to three", lambda c, where=where: c[where]["g_at_ends"].append(
                c[where]["g_at_ends"][-1]))
            edit(f"{where}.g_at_ends an object", lambda c, where=where: c[where].__setitem__(
                "g_at_ends", {"0": c[where]["g_at_ends"][0], "1": c[where]["g_at_ends"][1]}))
    if kind == "pitchfork":
        edit("summary.half_map_multipliers grown to three", lambda c: c["summary"]["half_map_multipliers"].append(
            [5.0, 5.0]))
        edit("summary.half_map_multipliers' first deleted", lambda c: c["summary"]["half_map_multipliers"].pop(0))
        edit("summary.half_map_multipliers an object", lambda c: c["summary"].__setitem__(
            "half_map_multipliers", {"0": [-1, -1]}))
    if kind == "orbit-pitchfork":
        edit("summary.symmetric false", lambda c: c["summary"].__setitem__("symmetric", False))
        edit("summary.symmetric of the wrong type", lambda c: c["summary"].__setitem__("symmetric", "yes"))
    if kind == "grazing":
        edit("bifurcation.unknowns' first entry a number", lambda c: c["bifurcation"]["unknowns"].__setitem__(0, 5))
        edit("bifurcation.unknowns renamed", lambda c: c["bifurcation"]["unknowns"].__setitem__(0, "s"))
    return out


class Truth:
    """The damped modal model of a certificate, at 50 digits."""

    def __init__(self, md):
        self.wi = [mpf(x) for x in md["frequencies"]]
        self.TA, self.TB, self.c = ([mpf(x) for x in md[k]] for k in ("forcing", "contact", "shape"))
        self.x0, self.r, self.f, self.w = (mpf(md[k]) for k in ("stop", "restitution", "amplitude", "frequency"))
        self.zeta = [mpf(x) for x in md.get("damping", ["0"] * len(self.wi))]
        self.n = len(self.wi)
        self.T = 2 * pi / self.w
        # Every contact (c_j, T_j, e_j, r_j, W_jj = c_j·T_j): contact 0 is the model's own fields.
        more = [([mpf(x) for x in k["shape"]], [mpf(x) for x in k["contact"]], mpf(k["stop"]), mpf(k["restitution"]))
                for k in md.get("more_contacts", [])]
        self.contacts = [(c, T, e, r, sum(x * y for x, y in zip(c, T)))
                         for c, T, e, r in [(self.c, self.TB, self.x0, self.r)] + more]

    def state(self, t0, X, V, t):
        """The free flight from (t0, X, V) to time t."""
        Xo, Vo = [], []
        w = self.w
        for i in range(self.n):
            wi, z = self.wi[i], self.zeta[i]
            sg, wd = z * wi, wi * sqrt(1 - z * z)
            # Ü + 2σU̇ + ω_i²U = T_A f sin ωt with U = P sin ωt + Q cos ωt.
            A = matrix([[wi ** 2 - w ** 2, -2 * sg * w], [2 * sg * w, wi ** 2 - w ** 2]])
            P, Q = mp.lu_solve(A, matrix([self.TA[i] * self.f, 0]))
            U = lambda t_: P * sin(w * t_) + Q * cos(w * t_)  # noqa: E731
            Ud = lambda t_: w * (P * cos(w * t_) - Q * sin(w * t_))  # noqa: E731
            a = X[i] - U(t0)
            b = (V[i] - Ud(t0) + sg * a) / wd
            s = t - t0
            e = exp(-sg * s)
            Xo.append(U(t) + e * (a * cos(wd * s) + b * sin(wd * s)))
            Vo.append(Ud(t) + e * ((b * wd - sg * a) * cos(wd * s) - (a * wd + sg * b) * sin(wd * s)))
        return Xo, Vo

    def gap(self, X, j=0):
        c, T, e, r, W = self.contacts[j]
        return sum(ci * x for ci, x in zip(c, X)) - e

    def rate(self, V, j=0):
        return sum(ci * v for ci, v in zip(self.contacts[j][0], V))

    def impact(self, V, j=0):
        c, T, e, r, W = self.contacts[j]
        p = -(1 + r) * self.rate(V, j) / W
        return [V[i] + p * T[i] for i in range(self.n)]


def scene_model(cert):
    """The modal model the theorem is about, at 50 digits: the certificate's model, or for a physical
    scene (a certificate with "structure": its mass and stiffness matrices, contacts and damping) the
    modal data of those matrices computed here (docs/model.md §1.3): the eigenpairs of M⁻¹K (mpmath's
    eig), ascending; ψ scaled to a unit component at contact 0 (σ_0 w_0ᵀψ = 1); m = ψᵀMψ, ω = √λ,
    T_A = ψ(A)/m, T_B = 1/m, c = 1; contact j ≥ 1: c_j = σ_j w_jᵀψ, T_j = c_j/m. The stops,
    restitutions, amplitude and frequency are the model's decimals."""
    md = cert["model"]
    st = cert.get("structure")
    if st is None:
        return md
    M = matrix([[mpf(x) for x in row] for row in st["mass"]])
    K = matrix([[mpf(x) for x in row] for row in st["stiffness"]])
    N = M.rows
    E, ER = eig(mp.inverse(M) * K)
    order = sorted(range(N), key=lambda k: mp.re(E[k]))
    cs = [(c["dof"], c["partner"], 1 if c["side"] == "below" else -1) for c in st["contacts"]]

    def w(v, c):
        d, p, sg = c
        return sg * (v[d] - (v[p] if p >= 0 else 0))

    out = {k: md[k] for k in ("stop", "restitution", "amplitude", "frequency")}
    for key in ("frequencies", "forcing", "contact", "shape"):
        out[key] = []
    more = [{"shape": [], "contact": [], "stop": k["stop"], "restitution": k["restitution"]}
            for k in md.get("more_contacts", [])]
    s = lambda x: mp.nstr(mp.re(x), 45)  # noqa: E731
    for i in range(st["kept"]):
        k = order[i]
        phi = [ER[a, k] for a in range(N)]
        b = w(phi, cs[0])
        psi = [x / b for x in phi]
        mi = sum(psi[a] * M[a, c] * psi[c] for a in range(N) for c in range(N))
        out["frequencies"].append(s(sqrt(mp.re(E[k]))))
        out["forcing"].append(s(psi[st["forcing_dof"]] / mi))
        out["contact"].append(s(1 / mi))
        out["shape"].append("1")
        for j, mc in enumerate(more, start=1):
            cj = w(psi, cs[j])
            mc["shape"].append(s(cj))
            mc["contact"].append(s(cj / mi))
    if more:
        out["more_contacts"] = more
    if "damping" in st:
        out["damping"] = st["damping"][:st["kept"]]
    return out


def orbit_truth(cert):
    """Newton on the multiple-shooting map from the certificate's midpoint; the multipliers by
    central differences of the stroboscopic map; the closed-form determinant."""
    m = Truth(scene_model(cert))
    n, q = m.n, cert["period"]
    per = 2 * n + 1
    count = len(cert["midpoint"]) // per
    hits = cert.get("impact_contacts", [0] * count)

    def unpack(u, j):
        return u[j * per], u[j * per + 1:j * per + 1 + n], u[j * per + 1 + n:(j + 1) * per]

    def F(*u):
        out = []
        for j in range(count):
            k = (j + 1) % count
            t, X, V = unpack(u, j)
            tn, Xn, Vn = unpack(u, k)
            tn = tn + (q * m.T if j == count - 1 else 0)
            Xe, Ve = m.state(t, X, V, tn)
            Vp = m.impact(Ve, hits[k])
            out.append(m.gap(X, hits[j]))
            out += [Xe[i] - Xn[i] for i in range(n)] + [Vp[i] - Vn[i] for i in range(n)]
        return out

    u = mp.findroot(F, [mpf(x) for x in cert["midpoint"]], tol=mpf(10) ** -45)
    u = [u[i] for i in range(len(u))]
    times = [unpack(u, j)[0] for j in range(count)]
    vbefore = []
    for j in range(count):
        prev = (j - 1) % count
        t, X, V = unpack(u, prev)
        tn = times[j] + (q * m.T if prev == count - 1 else 0)
        vbefore.append(m.rate(m.state(t, X, V, tn)[1], hits[j]))
    # Every gap stays positive between the impacts (sampled): the orbit found is an orbit.
    positive = True
    for j in range(count):
        t, X, V = unpack(u, j)
        tn = times[(j + 1) % count] + (q * m.T if j == count - 1 else 0)
        for k in range(1, 200):
            Xk = m.state(t, X, V, t + (tn - t) * k / 200)[0]
            if any(m.gap(Xk, l) <= 0 for l in range(len(m.contacts))):
                positive = False
    # Stroboscopic map from t_s, a little after impact 0, over q periods.
    t0, X0, V0 = unpack(u, 0)
    ts = t0 + (times[1 % count] + (q * m.T if count == 1 else 0) - t0) / 3

    def strobe(z):
        t, X, V = ts, z[:n], z[n:]
        for j in range(1, count + 1):
            tg = times[j % count] + (q * m.T if j == count else 0)
            hit = hits[j % count]
            tl = mp.findroot(lambda tt: m.gap(m.state(t, X, V, tt)[0], hit), tg, tol=mpf(10) ** -48)
            Xe, Ve = m.state(t, X, V, tl)
            t, X, V = tl, Xe, m.impact(Ve, hit)
        Xe, Ve = m.state(t, X, V, ts + q * m.T)
        return Xe + Ve

    Xs, Vs = m.state(t0, X0, V0, ts)
    z0 = Xs + Vs
    h = mpf("1e-20")
    J = matrix(2 * n, 2 * n)
    for col in range(2 * n):
        zp, zm = list(z0), list(z0)
        zp[col] += h
        zm[col] -= h
        a, b = strobe(zp), strobe(zm)
        for row in range(2 * n):
            J[row, col] = (a[row] - b[row]) / (2 * h)
    mult = eig(J, left=False, right=False)
    det_closed = mp.fprod(m.contacts[h][3] ** 2 for h in hits) * exp(-q * m.T * sum(2 * z * wi for z, wi in zip(m.zeta, m.wi)))
    det_fd = mp.det(J)
    return {"times": times, "vbefore": vbefore, "hits": hits, "section": (t0, X0, V0), "multipliers": list(mult), "m": m,
            "positive": positive, "det": (det_fd, det_closed)}


def compare(label, s, tr, expect):
    """Every claim of the summary contains the truth."""
    m = tr["m"]
    expect(tr["positive"], f"{label}: the 50-digit orbit keeps the gap positive between its impacts")
    det_fd, det_closed = tr["det"]
    expect(abs(det_fd - det_closed) <= mpf("1e-20") * (1 + abs(det_closed)),
           f"{label}: det of the stroboscopic Jacobian {mp.nstr(det_fd, 15)} = r^2m e^(-qT sum 2 sigma) "
           f"{mp.nstr(det_closed, 15)}")
    ev = s["events"]
    expect(len(ev) == len(tr["times"]), f"{label}: {len(ev)} events, the truth has {len(tr['times'])} impacts")
    for j, e in enumerate(ev[:len(tr["times"])]):
        t = tr["times"][j]
        expect(e["contact"] == tr["hits"][j], f"{label}: impact {j} at contact {e['contact']}, the truth's {tr['hits'][j]}")
        expect(inside(t, e["time"]), f"{label}: impact {j} time {mp.nstr(t, 20)} in {e['time']}")
        ph = (m.w * t) % (2 * pi)
        expect(inside(ph, e["phase"]), f"{label}: impact {j} phase {mp.nstr(ph, 20)} in {e['phase']}")
        expect(inside(tr["vbefore"][j], e["velocity_before"]),
               f"{label}: impact {j} velocity before {mp.nstr(tr['vbefore'][j], 20)} in {e['velocity_before']}")
    t0, X0, V0 = tr["section"]
    sec = s["section"]
    expect(inside(t0, sec["time"]) and all(inside(x, p) for x, p in zip(X0, sec["X"])) and
           all(inside(v, p) for v, p in zip(V0, sec["V"])), f"{label}: the section state contains the truth")
    claims = s["multipliers"]
    used = set()
    for mu in tr["multipliers"]:
        hit = next((k for k, c in enumerate(claims) if k not in used and inside(mp.re(mu), c["re"]) and
                    inside(mp.im(mu), c["im"])), None)
        expect(hit is not None, f"{label}: the multiplier {mp.nstr(mu, 15)} lies in a claimed enclosure ({claims})")
        if hit is not None:
            used.add(hit)
    moduli = [abs(mu) for mu in tr["multipliers"]]
    want = "unstable" if max(moduli) > 1 else "stable"
    expect(s["stability"] in (want, "undecided"), f"{label}: stability {s['stability']} (moduli {moduli})")
    width = max(mpf(p[1]) - mpf(p[0]) for p in [sec["time"]] + sec["X"] + sec["V"])
    expect(width <= mpf("1e-9"), f"{label}: the section enclosed within 1e-9 ({mp.nstr(width, 3)})")
