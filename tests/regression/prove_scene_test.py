"""`vibro prove` on the scene as written (docs/prove.md, "The scene as written"): for a scene in the
physical form the modal data of the proof are enclosures of the eigenpairs of K φ = ω² M φ, carried
in the certificate's "structure" and re-proven by the checker from the scene's matrices.

The truth is independent of vibro and of the checker: the eigenpairs at 50 digits by mpmath's
symmetric eigensolver on L⁻¹KL⁻ᵀ (M = LLᵀ, Cholesky), each eigenvector scaled to a unit component
at contact 0, and the modal data of docs/model.md §1.3 computed from them here; the orbit by Newton at
50 digits on the shooting map of those modal data (prove_truth.py). Checked:
- every enclosed eigenvalue, eigenvector component and modal datum contains the 50-digit value, and
  is at most 1e-13 wide (relative);
- the orbit's enclosures contain the 50-digit orbit of the scene's modal data;
- the checker confirms, and rejects every edit of the matrices, the contacts, the eigenpair boxes,
  the kept modes, the damping and the modal data;
- a scene with a repeated natural frequency is refused with the reason docs/prove.md lists.
"""
import copy
import json
import os
import sys

from mpmath import mp, mpf, sqrt, matrix, cholesky, eigsy, inverse

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from prove_truth import Harness, orbit_truth, compare  # noqa: E402

mp.dps = 50
VIBRO, CHECKER, SCENES = sys.argv[1:4]
H = Harness(VIBRO, CHECKER, "vibro_prove_scene_")
TMP = H.tmp
expect, prove, check_doc, scene_file = H.expect, H.prove, H.check_doc, H.scene_file



def bounds(text):
    a, b = (mpf(x) for x in text[1:-1].split(","))
    return a, b


def encloses(text, x, width=mpf("1e-13")):
    a, b = bounds(text)
    return a <= x <= b and b - a <= width * (1 + abs(x))





def modal_truth(M, K, forcing_dof, contacts):
    """The eigenpairs (ascending) and the modal data of docs/model.md §1.3 at 50 digits.
    contacts: (dof, partner, sign) per contact, contact 0 first."""
    M, K = matrix(M), matrix(K)
    N = M.rows
    L = cholesky(M)
    Li = inverse(L)
    lam, Y = eigsy(Li * K * Li.T)
    Phi = Li.T * Y  # K φ = λ M φ
    order = sorted(range(N), key=lambda k: lam[k])

    def w(v, c):
        d, p, sg = c
        return sg * (v[d] - (v[p] if p >= 0 else 0))

    modes = []
    for k in order:
        phi = [Phi[a, k] for a in range(N)]
        psi = [x / w(phi, contacts[0]) for x in phi]
        m = sum(psi[a] * M[a, b] * psi[b] for a in range(N) for b in range(N))
        modes.append({"lambda": lam[k], "psi": psi, "omega": sqrt(lam[k]), "forcing": psi[forcing_dof] / m,
                      "contact": 1 / m, "more": [(w(psi, c), w(psi, c) / m) for c in contacts[1:]]})
    return modes


def scene_checks(label, cert, M, K, forcing_dof, contacts):
    """The certificate's eigenpair boxes and modal data against the 50-digit truth."""
    st, md = cert["structure"], cert["model"]
    truth = modal_truth(M, K, forcing_dof, contacts)
    expect(cert["summary"]["modal_data"] == "enclosed", f"{label}: summary.modal_data 'enclosed'")
    expect(len(st["modes"]) == len(truth), f"{label}: every eigenpair of the {len(truth)} DOFs enclosed")
    for k, (box, t) in enumerate(zip(st["modes"], truth)):
        expect(encloses(box["eigenvalue"], t["lambda"]),
               f"{label}: mode {k}: the eigenvalue box {box['eigenvalue']} holds the 50-digit λ = {mp.nstr(t['lambda'], 20)}")
        expect(all(encloses(b, x) for b, x in zip(box["vector"], t["psi"])),
               f"{label}: mode {k}: the eigenvector boxes {box['vector']} hold ψ = {[mp.nstr(x, 17) for x in t['psi']]}")
    for i in range(st["kept"]):
        t = truth[i]
        for key, x in (("frequencies", t["omega"]), ("forcing", t["forcing"]), ("contact", t["contact"])):
            expect(encloses(md[key][i], x),
                   f"{label}: model.{key}[{i}] = {md[key][i]} holds the 50-digit {mp.nstr(x, 20)}")
        for j, (cj, Tj) in enumerate(t["more"]):
            mc = md["more_contacts"][j]
            expect(encloses(mc["shape"][i], cj) and encloses(mc["contact"][i], Tj),
                   f"{label}: contact {j + 1}, mode {i}: {mc['shape'][i]}, {mc['contact'][i]} hold "
                   f"{mp.nstr(cj, 17)}, {mp.nstr(Tj, 17)}")


def shifted(text, by):
    a, b = bounds(text)
    return f"[{mp.nstr(a + by, 25)}, {mp.nstr(b + by, 25)}]"


def edits(label, cert):
    """Every edit of the scene's matrices, contacts, eigenpair boxes, kept modes, damping and modal
    data is rejected (exit 1 or 2)."""
    st, md = cert["structure"], cert["model"]
    N = len(st["mass"])
    lam1 = bounds(st["modes"][1]["eigenvalue"])
    cases = [
        ("mass[0][0] moved by 1e-6", lambda c: c["structure"]["mass"][0].__setitem__(
            0, mp.nstr(mpf(st["mass"][0][0]) * (1 + mpf("1e-6")), 25))),
        ("stiffness[0][1] and [1][0] moved by 1e-9", lambda c: [c["structure"]["stiffness"][a].__setitem__(
            b, mp.nstr(mpf(st["stiffness"][a][b]) + mpf("1e-9"), 25)) for a, b in ((0, 1), (1, 0))]),
        ("stiffness[0][1] alone moved (not symmetric)", lambda c: c["structure"]["stiffness"][0].__setitem__(
            1, mp.nstr(mpf(st["stiffness"][0][1]) + mpf("1e-9"), 25))),
        ("eigenvalue box of mode 0 moved by 1e-9", lambda c: c["structure"]["modes"][0].__setitem__(
            "eigenvalue", shifted(st["modes"][0]["eigenvalue"], mpf("1e-9")))),
        ("an eigenvector box moved by 1e-9", lambda c: c["structure"]["modes"][0]["vector"].__setitem__(
            0, shifted(st["modes"][0]["vector"][0], mpf("1e-9")))),
        ("modes 0 and 1 swapped", lambda c: c["structure"]["modes"].reverse() if N == 2 else
         c["structure"]["modes"].insert(0, c["structure"]["modes"].pop(1))),
        ("eigenvalue box of mode 0 widened over mode 1's", lambda c: c["structure"]["modes"][0].__setitem__(
            "eigenvalue", f"[{bounds(st['modes'][0]['eigenvalue'])[0]}, {mp.nstr(lam1[1], 25)}]")),
        ("a mode left out", lambda c: c["structure"]["modes"].pop()),
        ("model.frequencies[0] a point 1e-9 off", lambda c: c["model"]["frequencies"].__setitem__(
            0, mp.nstr(bounds(md["frequencies"][0])[0] - mpf("1e-9"), 25))),
        ("model.forcing[0] narrowed to its lower tenth", lambda c: c["model"]["forcing"].__setitem__(
            0, "[{}, {}]".format(*(mp.nstr(x, 25) for x in (bounds(md["forcing"][0])[0], bounds(md["forcing"][0])[0] +
                                                              (bounds(md["forcing"][0])[1] - bounds(md["forcing"][0])[0]) / 10))))),
        ("model.contact[1] moved by 1e-9", lambda c: c["model"]["contact"].__setitem__(
            1, shifted(md["contact"][1], mpf("1e-9")))),
        ("model.shape[0] = 1.000001", lambda c: c["model"]["shape"].__setitem__(0, "1.000001")),
        ("the force at another DOF", lambda c: c["structure"].__setitem__("forcing_dof", (st["forcing_dof"] + 1) % N)),
        ("contact 0 on the other side", lambda c: c["structure"]["contacts"][0].__setitem__(
            "side", "above" if st["contacts"][0]["side"] == "below" else "below")),
        ("contact 0 on another DOF", lambda c: c["structure"]["contacts"][0].__setitem__(
            "dof", (st["contacts"][0]["dof"] + 1) % N)),
        ("one kept mode fewer", lambda c: c["structure"].__setitem__("kept", st["kept"] - 1)),
        ("the structure left out", lambda c: c.pop("structure")),
        ("modal_data 'given' beside the structure", lambda c: c["summary"].__setitem__("modal_data", "given")),
    ]
    if len(st["contacts"]) > 1:
        cases += [("contact 1 on another DOF", lambda c: c["structure"]["contacts"][1].__setitem__(
            "dof", (st["contacts"][1]["dof"] + 1) % N)),
            ("contact 1's modal shape moved by 1e-9", lambda c: c["model"]["more_contacts"][0]["shape"].__setitem__(
                0, shifted(md["more_contacts"][0]["shape"][0], mpf("1e-9"))))]
    if "damping" in st:
        cases += [("the scene's damping ratio of mode 0 moved by 1e-6", lambda c: c["structure"]["damping"].__setitem__(
            0, mp.nstr(mpf(st["damping"][0]) + mpf("1e-6"), 20))),
            ("the model's damping of mode 0 moved by 1e-6", lambda c: c["model"]["damping"].__setitem__(
                0, mp.nstr(mpf(md["damping"][0]) + mpf("1e-6"), 20))),
            ("the scene's damping left out", lambda c: c["structure"].pop("damping"))]
    for name, edit in cases:
        c = copy.deepcopy(cert)
        edit(c)
        code, v = check_doc(c)
        expect(code in (1, 2), f"{label}: {name}: rejected (exit {code}, {v and v['reason'][:200]})")


def proven(label, scene, M, K, forcing_dof, contacts, *args):
    path = os.path.join(TMP, label.replace(" ", "_") + ".json")
    code, s, err = prove(scene, *args, out=path)
    expect(code == 0 and s and s["verdict"] == "proven", f"{label}: proven (exit {code}: {s and s['reason']} {err[-300:]})")
    if code != 0:
        return None
    cert = json.load(open(path))
    scene_checks(label, cert, M, K, forcing_dof, contacts)
    compare(label, s, orbit_truth(cert), expect)
    code, v = check_doc(cert)
    expect(code == 0 and v["verdict"] == "confirmed", f"{label}: the checker confirms ({v})")
    return cert


# ---- The damped 2-DOF chain (M = I), one stop ---------------------------------------------------------
cert = proven("chain2 damped", os.path.join(SCENES, "chain2_damped.toml"), [[1, 0], [0, 1]], [[2, -1], [-1, 1]], 0,
              [(1, -1, 1)], "--kind", "impact", "--set", "excitation.amplitude=3")
if cert:
    edits("chain2 damped", cert)

# ---- The tube in its loose support: M = diag(2, 1), two contacts on DOF 1, damped ----------------------
cert = proven("tube", os.path.join(SCENES, "tube_loose_support.toml"), [[2, 0], [0, 1]], [[4, -1], [-1, 1]], 0,
              [(1, -1, 1), (1, -1, -1)])
if cert:
    edits("tube", cert)

# ---- A 3-DOF chain with a coupled mass matrix: a stop on DOF 2 and an impact pair q1 − q2 ≥ −0.9 ------
# (five impacts per period at both contacts), damping ratios differing per mode; and truncated to its
# two lowest modes (`modes = 2`).
C3 = """title = "3-DOF chain, coupled mass matrix, a stop and an impact pair"
[structure]
mass        = [[1.0, 0.2, 0.0], [0.2, 2.0, 0.1], [0.0, 0.1, 0.5]]
stiffness   = [[2.5, -1.5, 0.0], [-1.5, 2.3, -0.8], [0.0, -0.8, 0.8]]
forcing_dof = 0
damping_ratios = [0.02, 0.03, 0.05]
{modes}
[[contact]]
dof = 2
side = "below"
position = -0.5
restitution = 0.6
[[contact]]
dofs = [1, 2]
side = "below"
position = -0.9
restitution = 0.5
[excitation]
amplitude = 0.3
frequency = 0.5
[run]
periods = 300
"""
M3 = [[1, mpf("0.2"), 0], [mpf("0.2"), 2, mpf("0.1")], [0, mpf("0.1"), mpf("0.5")]]
K3 = [[mpf("2.5"), mpf("-1.5"), 0], [mpf("-1.5"), mpf("2.3"), mpf("-0.8")], [0, mpf("-0.8"), mpf("0.8")]]
for label, modes in (("coupled 3-DOF", ""), ("coupled 3-DOF, modes = 2", "modes = 2")):
    cert = proven(label, scene_file(label.replace(" ", "_").replace(",", "").replace("=", "") + ".toml",
                                    C3.format(modes=modes)), M3, K3, 0, [(2, -1, 1), (1, 2, 1)], "--kind", "impact")
    if cert:
        expect(cert["structure"]["kept"] == (2 if modes else 3) and len(cert["model"]["frequencies"]) == cert["structure"]["kept"],
               f"{label}: {cert['structure']['kept']} modes kept of 3")
        expect(set(cert["impact_contacts"]) == {0, 1}, f"{label}: impacts at both contacts ({cert['impact_contacts']})")
        if not modes:
            edits(label, cert)

# ---- Refused: a repeated natural frequency (M = I, K = I: ω = 1 twice) --------------------------------
code, s, err = prove(scene_file("repeated.toml", """title = "repeated natural frequency"
[structure]
mass        = [[1.0, 0.0], [0.0, 1.0]]
stiffness   = [[1.0, 0.0], [0.0, 1.0]]
forcing_dof = 0
contact_dof = 1
[stop]
position = 0.5
restitution = 0.8
[excitation]
amplitude = 1.0
frequency = 0.7
"""), "--kind", "impact")
docs = open(os.path.join(os.path.dirname(SCENES), "..", "docs", "prove.md")).read()
expect(code == 4 and s and "could not be enclosed with every eigenvalue simple" in s["reason"] and
       "could not be enclosed with every eigenvalue simple" in docs.replace("\n  ", " "),
       f"a repeated natural frequency: not proven, the reason docs/prove.md lists (exit {code}: {s and s['reason']} {err[-200:]})")

H.finish()
