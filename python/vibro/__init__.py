"""vibro: harmonically forced impact oscillators with sticking and chattering, from Python.

Every function runs the same computation as the command of the same name and returns what its
``--json`` prints, as a dict (see docs/python.md). Bad input raises ``ValueError`` whose message
names the file, line, column, key and violated constraint; Ctrl-C stops a computation cleanly,
keeps what was written to ``out`` and then raises ``KeyboardInterrupt``.

    >>> import vibro
    >>> scene = vibro.load_scene("data/scenes/fig08_preload.toml", set={"run.periods": 50})
    >>> run = vibro.simulate(scene)
    >>> run.summary["attractor"]["sticking_fraction"]
"""
import json as _json
import math as _math
import os as _os
import sys as _sys
import threading as _threading
from collections.abc import Mapping as _Mapping


def _limit_blas_threads():
    """One OpenBLAS thread under an address-space limit (``ulimit -v``, RLIMIT_AS), unless the user
    chose ``OPENBLAS_NUM_THREADS``. Each OpenBLAS thread reserves a 128 MB buffer when it starts and
    retries forever when the limit refuses it: the thread spins, and the interpreter hangs at exit
    joining it (docs/python.md, "Under a memory limit"). vibro does not use BLAS threads; numpy
    reads the variable once, when it is first imported, so this must run before ``import numpy``."""
    try:
        import resource
        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, OSError, ValueError):
        return
    if soft != resource.RLIM_INFINITY and "numpy" not in _sys.modules:
        _os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


_limit_blas_threads()

import numpy as _np  # noqa: E402

from . import _vibro

#: A run ended by its limits (time, disk): ``simulate(..., time_limit=...)``, as ``vibro simulate``
#: exits 3. Its message is one line saying why ("1.0·10⁹ impacts per time unit: ...").
LimitError = _vibro.LimitError

__version__ = _vibro.version
git_commit = _vibro.git_commit

class _EventKinds(dict):
    """int → name, as a dict; a name gives its int too (``EVENT_KINDS["release"] == 4``)."""

    def __missing__(self, key):
        if isinstance(key, str):
            for code, name in self.items():
                if name == key:
                    return code
        raise KeyError(key)

    def __contains__(self, key):
        return dict.__contains__(self, key) or (isinstance(key, str) and key in self.values())

    def get(self, key, default=None):
        return self[key] if key in self else default


#: Event kinds as stored in ``events["kind"]`` and in HDF5 files (the enum of /events/kind):
#: ``EVENT_KINDS[4] == "release"`` and ``EVENT_KINDS["release"] == 4``.
EVENT_KINDS = _EventKinds({1: "impact", 2: "accumulation", 3: "stick", 4: "release", 5: "grazing"})
#: Motion modes of ``samples["mode"]``: 0 free flight, 1 sticking.
MODES = {0: "free", 1: "sticking"}

__all__ = ["Scene", "SimulationResult", "Group", "load_scene", "model", "simulate", "orbit", "prove", "prove_bifurcation", "prove_segment", "continue_", "curve",
           "diagram",
           "attractors", "basin", "sweep", "check", "info", "validate", "score", "partition", "read",
           "EVENT_KINDS", "MODES", "LOAD_FIELDS", "COMPLIANT_LOAD_FIELDS", "LimitError"]


def _toml_value(value):
    """A Python value as TOML (the VALUE of --set KEY=VALUE)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not _math.isfinite(value):
            raise ValueError(f"{value!r}: scene values must be finite numbers")
        return repr(value)
    if isinstance(value, str):
        return _json.dumps(value)  # a TOML basic string
    if isinstance(value, (list, tuple, _np.ndarray)):
        return "[" + ", ".join(_toml_value(v.item() if hasattr(v, "item") else v) for v in value) + "]"
    if isinstance(value, _np.generic):
        return _toml_value(value.item())
    raise ValueError(f"{value!r}: cannot be written as a TOML value (expected a number, bool, "
                     "string or list)")


def _overrides(set):
    if set is None:
        return []
    if isinstance(set, dict):
        return [f"{k}={_toml_value(v)}" for k, v in set.items()]
    return [str(s) for s in set]  # already "KEY=VALUE" strings, as on the command line


class Scene:
    """A validated scene, as it will be run (after overrides).

    ``text`` is the scene as TOML (what outputs store), ``source`` the file or name it came from.
    Build one with :func:`load_scene` or :meth:`Scene.from_toml`.
    """

    def __init__(self, core):
        self._core = core

    @classmethod
    def from_toml(cls, text, source="<string>", set=None):
        """Parses TOML text; ``source`` names it in error messages (``source:line:col``)."""
        return cls(_vibro.parse_scene(text, source, _overrides(set)))

    @property
    def text(self):
        return self._core.text

    @property
    def source(self):
        return self._core.source

    @property
    def title(self):
        return self._core.title

    def with_(self, set):
        """This scene with more overrides (a dict KEY: value, as ``set=`` of load_scene)."""
        return Scene.from_toml(self.text, self.source, set)

    def __repr__(self):
        return f"vibro.Scene({self.source!r}{', ' + repr(self.title) if self.title else ''})"


def load_scene(path, set=None):
    """Reads and validates a scene file. ``set`` overrides keys, e.g.
    ``{"excitation.amplitude": 2.5, "run.engine": "exact"}`` (like ``--set KEY=VALUE``)."""
    return Scene(_vibro.load_scene(_path("path", path), _overrides(set)))


def _int(name, value):
    """An integer argument (int, numpy integer, or a float of integral value); its range is checked
    by the C++ module, as the command line checks it."""
    if isinstance(value, (float, _np.floating)) and _math.isfinite(value) and float(value).is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, (int, _np.integer)):
        raise ValueError(f"{name} {value!r}: expected an integer, got {type(value).__name__}")
    if not -2 ** 63 < int(value) < 2 ** 63:  # every limit is far inside; the module checks those
        raise ValueError(f"{name} {int(value)}: expected a 64-bit integer (and within the limit of {name})")
    return int(value)


def _seed(value):
    seed = _int("seed", value)
    if not 0 <= seed < 2 ** 63 - 1:
        raise ValueError(f"seed {value!r}: expected an integer in [0, 2^63 - 1)")
    return seed


def _float(name, value):
    """A number argument (nan and inf are refused by the C++ module where the command line
    refuses them)."""
    if isinstance(value, bool):
        raise ValueError(f"{name} {value!r}: expected a number, got bool")
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} {value!r}: expected a number, got {type(value).__name__}") from None


def _path(name, value):
    """A file name argument: str or os.PathLike (bytes are refused: names are text)."""
    if isinstance(value, str):
        return value
    if isinstance(value, _os.PathLike):
        v = _os.fspath(value)
        if isinstance(v, str):
            return v
    raise ValueError(f"{name} {value!r}: expected a file name (str or os.PathLike), got {type(value).__name__}")


def _out(value):
    return "" if value is None else _path("out", value)


def _scene(scene):
    if isinstance(scene, Scene):
        return scene._core
    return load_scene(scene)._core  # a path


def _invoke(command, scene, **options):
    """Provenance of the files the next call writes: the command, the Python call and its options
    (root attributes command, command_line and options); `force` lets `out` replace a vibro file
    of another scene or command."""
    force = bool(options.pop("force", False))
    source = scene.source if isinstance(scene, Scene) else str(scene)
    shown = {k: (str(v) if k == "out" and v is not None else v) for k, v in options.items()}
    call = f"vibro.{command}({source!r}" + "".join(f", {k}={v!r}" for k, v in shown.items()) + ")"
    _vibro.set_invocation(command.rstrip("_"), call, _json.dumps(shown, default=str, sort_keys=True), force)


def _main_thread():
    return _threading.current_thread() is _threading.main_thread()


def _in_notebook():
    """Whether Python runs in a Jupyter kernel (where a call shows a progress bar by default)."""
    import sys
    shell = sys.modules.get("IPython")
    try:
        ip = shell.get_ipython() if shell else None
    except Exception:  # noqa: BLE001 (an IPython without a running shell)
        return False
    return ip is not None and type(ip).__name__ == "ZMQInteractiveShell"


def _bar_class():
    """tqdm's bar as tqdm.auto chooses it: a widget in a notebook with ipywidgets, else text (on
    stderr, in a notebook's output too). Chosen here because tqdm.auto warns in a notebook without
    ipywidgets before it falls back to text."""
    if _in_notebook():
        try:
            import ipywidgets  # noqa: F401
            from tqdm.notebook import tqdm
            return tqdm
        except ImportError:
            pass
    from tqdm.std import tqdm
    return tqdm


def _progress(progress, what, unit):
    """The callable the C++ module reports progress(done, total) to (None: no report) and what closes
    it afterwards. ``progress`` is False (no report), True (a tqdm bar: a widget in a notebook, text
    on a terminal; tqdm.auto), a callable, or None: a bar in a Jupyter notebook, nothing in a
    script."""
    if progress is None:
        progress = _in_notebook()
    if progress is False:
        return None, lambda: None
    if progress is True:
        try:
            tqdm = _bar_class()
        except ImportError:
            raise ValueError("progress=True: needs the tqdm package (Debian: python3-tqdm; pip: tqdm); "
                             "or give a callable progress(done, total)") from None
        bar = tqdm(desc=f"vibro {what}", unit=unit, dynamic_ncols=True, delay=0.5)  # nothing for a short call

        def report(done, total):
            if bar.total != total:
                bar.total = total
            if done > bar.n:
                bar.update(done - bar.n)
            else:
                bar.refresh()

        return report, bar.close
    if callable(progress):
        return progress, lambda: None
    raise ValueError(f"progress {progress!r}: expected True, False, None or a callable progress(done, total), "
                     f"got {type(progress).__name__}")


def _with_progress(progress, what, unit, call):
    """call(callback) with the progress report of ``progress``, closed afterwards whatever happens."""
    report, close = _progress(progress, what, unit)
    try:
        return call(report)
    finally:
        close()


def _interrupted(what, out):
    kept = f"; {out} keeps everything computed so far" if out else ""
    return KeyboardInterrupt(f"vibro: {what} interrupted{kept}")


def model(scene):
    """The model as vibro understands the scene (the dict of ``vibro model --json``)."""
    return _json.loads(_vibro.model(_scene(scene)))


def _events_array(e):
    a = _np.empty(len(e["t"]), dtype=[("t", "f8"), ("kind", "i1"), ("x_B", "f8"), ("v_before", "f8"),
                                      ("v_after", "f8"), ("contact", "i4"), ("simultaneous", "?"),
                                      ("impulse", "f8"), ("energy_dissipated", "f8"), ("stick_duration", "f8"),
                                      ("reaction_integral", "f8"), ("reaction_max", "f8"), ("peak_time", "f8"),
                                      ("penetration_max", "f8")])
    for k in a.dtype.names:
        a[k] = e[k]
    return a


def _rows_array(r):
    n = r["X"].shape[1] if r["X"].ndim == 2 else 0
    a = _np.empty(len(r["t"]), dtype=[("t", "f8"), ("X", "f8", (n,)), ("V", "f8", (n,)), ("x_B", "f8"),
                                      ("mode", "i1")])
    for k in a.dtype.names:
        a[k] = r[k]
    return a


class SimulationResult:
    """What :func:`simulate` returns.

    - ``summary``: the dict of ``vibro simulate --json`` (status, engine, t_end, counts, attractor);
    - ``events``: structured array, fields t, kind (:data:`EVENT_KINDS`), x_B, v_before, v_after, contact (the
      ``[[contact]]`` index, docs/contacts.md), simultaneous, and what the contacts endure (docs/loads.md):
      impulse, energy_dissipated, and for a release stick_duration, reaction_integral, reaction_max (NaN
      otherwise), and for a compliant contact phase's release peak_time (the peak force's instant) and
      penetration_max (its largest penetration; NaN otherwise, docs/compliant.md); ``summary["loads"]``
      holds the per-contact means and intervals;
    - ``samples``: structured array of the dense output, fields t, X (n,), V (n,), x_B, mode;
    - ``section``: the stroboscopic section (t0 + kT), same fields as ``samples``.
    """

    def __init__(self, summary, events, samples, section):
        self.summary, self.events, self.samples, self.section = summary, events, samples, section

    def __repr__(self):
        a = self.summary.get("attractor", {})
        return (f"SimulationResult(status={self.summary.get('status')!r}, attractor={a.get('kind')!r}, "
                f"{len(self.events)} events, {len(self.samples)} samples)")


def simulate(scene, out=None, force=False, resume=False, extend=None, progress=None, blocks=10, time_limit=86400.0):
    """Simulates the scene (``vibro simulate``); with ``out`` also writes the HDF5 file (``force``:
    replace a vibro file of another scene or command).

    ``resume=True`` takes up the interrupted run stored in ``out`` at its last checkpoint
    (``--resume``); ``extend=N`` continues the run stored in ``out``, finished or interrupted, for
    N more periods (``--extend N``; the scene is the stored one with ``run.periods`` the new
    total). Either way the file ends with the same bits as an uninterrupted run of its total
    length; the result's arrays hold the part this call computed, its summary the whole run's
    attractor. ``progress``: True for a progress bar (tqdm; a widget in a notebook), False for
    none, or a callable ``progress(done, total)`` called with the periods done, at most ten times a
    second and once at the end; None (the default) shows a bar in a Jupyter notebook only.
    ``blocks``: the contact loads' intervals are batch means over this many blocks of periods
    (``--blocks``, docs/loads.md). ``time_limit``: seconds for the whole run (``--time-limit``;
    default one day, 0 for none): a run whose event rate would take it past the limit, or past
    its disk's free space with ``out``, raises :class:`LimitError` at once with one line ("1.0·10⁹
    impacts per time unit: ..."), ``out`` keeping what was written up to its last flush."""
    _invoke("simulate", scene, out=out, force=force, **({"resume": True} if resume else {}),
            **({"extend": extend} if extend is not None else {}))
    if not isinstance(resume, (bool, _np.bool_)):
        raise ValueError(f"resume {resume!r}: expected True or False, got {type(resume).__name__}")
    ext = None if extend is None else _int("extend", extend)
    nblocks = _int("blocks", blocks)
    if not 2 <= nblocks <= 100000:
        raise ValueError(f"blocks {blocks!r}: expected 2 to 100000 blocks (an interval needs two)")
    limit = _float("time_limit", time_limit)
    core = _scene(scene)
    r = _with_progress(progress, "simulate", "period",
                       lambda report: _vibro.simulate(core, _out(out), bool(resume), ext, report, _main_thread(),
                                                      nblocks, limit))
    if r["interrupted"]:
        raise _interrupted("simulation", out)
    return SimulationResult(_json.loads(r["json"]), _events_array(r["events"]), _rows_array(r["samples"]),
                            _rows_array(r["section"]))


def rigid_beside(scene, blocks=10):
    """The rigid model beside a scene with compliant stops (``vibro simulate --rigid-beside``,
    docs/compliant.md): the scene is run as given and with every compliant stop made rigid, of the
    restitution e(ζ) its damping gives an isolated impact under its separation rule. Returns the
    dict of the JSON's ``rigid_model``: ``distance`` (max, time_of_max, at_end: the largest distance
    between the two trajectories over the dense samples, physical DOFs), ``contacts`` (per contact:
    zeta, restitution, phases, peak_force_max, peak_force_mean, duration_mean, and the ``compliant``
    and ``rigid`` loads: impulse_per_period, mean_force, dissipated_power, contact_fraction)."""
    nblocks = _int("blocks", blocks)
    if not 2 <= nblocks <= 100000:
        raise ValueError(f"blocks {blocks!r}: expected 2 to 100000 blocks (an interval needs two)")
    return _json.loads(_vibro.rigid_beside(_scene(scene), nblocks))


def orbit(scene, kind="auto", period=0, impacts=0, guess=None, out=None, force=False, transient=None):
    """Finds a periodic orbit with the Poincaré solver (``vibro orbit --json``). ``guess`` is the
    phase ωt of the release (or first impact), or (phase, contact velocity): Newton starts there
    unless ``transient`` periods are asked for. Without a guess, ``transient`` defaults to 200;
    ``transient=0`` starts Newton at the scene's initial state (``vibro orbit --transient 0``). With
    several contacts the dict also has ``sequence``, the orbit's contact sequence (docs/contacts.md;
    the orbit, its impacts and ``section_time`` reported from the start of its canonical rotation,
    docs/orbits.md "Where the orbit's listing starts"),
    and ``no_jacobian`` when the orbit has no multipliers (a simultaneous impact of coupled contacts)."""
    if transient is None:
        transient = 0 if guess is not None else 200
    _invoke("orbit", scene, kind=kind, period=period, impacts=impacts, guess=guess, out=out, force=force,
            transient=transient)
    phase = velocity = None
    if guess is not None:
        g = [guess] if _np.ndim(guess) == 0 else list(_np.ravel(guess)) if isinstance(guess, _np.ndarray) else guess
        if not isinstance(g, (list, tuple)) or not 1 <= len(g) <= 2:
            raise ValueError(f"guess {guess!r}: expected PHASE or (PHASE, VELOCITY)")
        phase = _float("guess", g[0])
        velocity = _float("guess", g[1]) if len(g) > 1 else None
    text, interrupted = _vibro.orbit(_scene(scene), kind, _int("period", period), _int("impacts", impacts), phase,
                                     velocity, _out(out), _int("transient", transient), _main_thread())
    if interrupted:
        raise _interrupted("orbit search", None)
    return _json.loads(text)


def prove(scene, kind="auto", period=0, transient=200, from_=None, out=None, time_limit=60.0):
    """Proves a periodic orbit in interval arithmetic (``vibro prove --json``, docs/prove.md): the dict
    has ``verdict`` ("proven" or "not-proven"), ``reason``, ``period``, ``sequence``, ``events``,
    ``section``, ``multipliers`` and ``stability``, enclosures as [lo, hi]. ``from_`` is a file of
    ``vibro orbit --out`` to start from; ``out`` receives the certificate (JSON), which
    ``vibro_check_proof.py`` re-verifies. ``time_limit`` bounds the whole call (the transient, the orbit
    search and the proof); Ctrl-C raises ``KeyboardInterrupt`` within a second, nothing proven or written."""
    text, certificate, interrupted = _vibro.prove(_scene(scene), kind, _int("period", period),
                                                  _int("transient", transient),
                                                  "" if from_ is None else _path("from_", from_),
                                                  _float("time_limit", time_limit), _main_thread())
    if interrupted:
        raise _interrupted("proof", None)
    if out is not None:
        with open(_path("out", out), "w", encoding="utf-8") as fh:
            fh.write(certificate + "\n")
    return _json.loads(text)


def prove_bifurcation(scene, kind, param, value, out=None, time_limit=60.0, branch=None):
    """Proves a bifurcation point (``vibro prove --bifurcation KIND:KEY=VALUE --json``, docs/prove.md
    "Bifurcation points"): ``kind`` and ``value`` as ``continue_`` reports the point (a
    "branch-point" or a "fold" of the symmetric two-sided oscillator, or a "grazing" of any impacting
    orbit, whose orbit is taken from ``branch``, the HDF5 file of ``continue_``: its stored point
    nearest ``value``), ``param`` the scene key it varies
    ("excitation.amplitude" or "excitation.frequency"). The dict has ``verdict``, ``reason`` and, when
    proven, ``bifurcation``, ``interval`` (two decimals, at most 1e-10 apart, holding exactly one such
    point), ``slope`` (the derivative that proves the crossing transversal) and
    ``half_map_multipliers``. ``out`` receives the certificate, which ``vibro_check_proof.py``
    re-verifies."""
    text, certificate, interrupted = _vibro.prove_bifurcation(_scene(scene), str(kind), str(param),
                                                              _float("value", value),
                                                              _float("time_limit", time_limit), _main_thread(),
                                                              "" if branch is None else _path("branch", branch))
    if interrupted:
        raise _interrupted("proof", None)
    if out is not None:
        with open(_path("out", out), "w", encoding="utf-8") as fh:
            fh.write(certificate + "\n")
    return _json.loads(text)


def prove_segment(scene, param, lo, hi, branch=None, out=None, time_limit=60.0):
    """Proves the segment of ``vibro prove --branch`` between two parameter values (docs/prove.md
    "Along a branch"): for every value of ``param`` ("excitation.amplitude",
    "excitation.frequency", the stop position or the restitution) in [``lo``, ``hi``], exactly one
    impacting orbit with the ends' impact sequence in the box of each piece (the interval halved up
    to 5 times). Each end's orbit is ``branch``'s stored point at that value (the HDF5 file of
    ``continue_``), or without a branch the one the scene's start reaches. Returns the list of the
    pieces' dicts (``verdict``, ``reason``, ``events``, ...); ``out`` receives
    ``{"certificates": [...]}``, which ``vibro_check_proof.py`` re-verifies."""
    text, certificates, interrupted = _vibro.prove_segment(_scene(scene), str(param), _float("lo", lo),
                                                           _float("hi", hi),
                                                           "" if branch is None else _path("branch", branch),
                                                           _float("time_limit", time_limit), _main_thread())
    if interrupted:
        raise _interrupted("proof", None)
    if out is not None:
        with open(_path("out", out), "w", encoding="utf-8") as fh:
            fh.write('{"certificates": ' + certificates + "}\n")
    return _json.loads(text)


def _branch_table(points):
    t = _np.empty(len(points), dtype=[("value", "f8"), ("sticking_fraction", "f8"), ("stable", "?")])
    for i, p in enumerate(points):
        sf = p.get("sticking_fraction")
        t[i] = (p["value"], _np.nan if sf is None else sf, bool(p["stable"]))
    return t


LOAD_FIELDS = ("impacts_per_period", "impulse_per_period", "reaction_integral_per_period", "mean_force",
               "dissipated_power", "work_rate", "contact_fraction")
# A compliant stop's loads besides LOAD_FIELDS (docs/loads.md, "Peak force and contact duration over
# a run"): contact phases per period, mean certified peak force and mean duration per phase, the
# largest peak. Rigid contacts have none (NaN).
COMPLIANT_LOAD_FIELDS = ("contact_phases_per_period", "peak_force_mean", "contact_duration_mean", "peak_force_max")


def _loads_arrays(rows):
    """Per-row contact loads (the "loads" lists of branch points or partition cells) as a dict
    field → array of shape (rows, m), m the most contacts of any row; NaN where a row has no value
    (no loads, a contact it lacks, or a load reported unknown, null in the JSON; docs/loads.md).
    The fields are LOAD_FIELDS, and COMPLIANT_LOAD_FIELDS too when a row has a compliant contact."""
    m = max([0] + [len(r.get("loads") or []) for r in rows])
    compliant = any("peak_force_mean" in c for r in rows for c in r.get("loads") or [])
    fields = LOAD_FIELDS + (COMPLIANT_LOAD_FIELDS if compliant else ())
    out = {k: _np.full((len(rows), m), _np.nan) for k in fields}
    for i, r in enumerate(rows):
        for c in r.get("loads") or []:
            for k in fields:
                if c.get(k) is not None:
                    out[k][i, int(c["contact"])] = c[k]
    return out


def _contact_phase_arrays(points):
    """A compliant stop's contact phases along a branch (each point's ``contact_phases``,
    docs/compliant.md "Along a continued branch") as a dict: ``peak_force`` and ``duration``, shape
    (points, contacts), the largest certified peak force and the longest duration of each contact's
    phases over the orbit's period (NaN: no phase), ``phases`` their number, and ``rigid_distance``,
    shape (points,), the rigid model's orbit's largest distance (NaN: none). None for a rigid scene."""
    if not any(p.get("contact_phases") for p in points):
        return None
    m = max([1] + [len(p.get("loads") or []) for p in points]
            + [int(c["contact"]) + 1 for p in points for c in p.get("contact_phases") or []])
    out = {"peak_force": _np.full((len(points), m), _np.nan), "duration": _np.full((len(points), m), _np.nan),
           "phases": _np.zeros((len(points), m), dtype=int), "rigid_distance": _np.full(len(points), _np.nan)}
    for i, p in enumerate(points):
        for c in p.get("contact_phases") or []:
            j = int(c["contact"])
            out["peak_force"][i, j] = _np.fmax(out["peak_force"][i, j], c["peak_force"])
            out["duration"][i, j] = _np.fmax(out["duration"][i, j], c["duration"])
            out["phases"][i, j] += 1
        if p.get("rigid_distance") is not None:
            out["rigid_distance"][i] = p["rigid_distance"]
    return out


def _strobe_array(points):
    """Each branch point's stroboscopic state (its ``strobe`` list: every contact's coordinate at
    t ≡ initial.time mod the orbit's period, docs/output.md) as an array (points, contacts); NaN
    where the JSON has null."""
    m = max([0] + [len(p.get("strobe") or []) for p in points])
    out = _np.full((len(points), m), _np.nan)
    for i, p in enumerate(points):
        for j, x in enumerate(p.get("strobe") or []):
            if x is not None:
                out[i, j] = x
    return out


def continue_(scene, param, to, step=0.0, max_points=1000, period=0, kind="auto", out=None, force=False, from_=None,
              point=None, switch=False, side="above"):
    """Continues a periodic orbit in ``param`` up to ``to`` (``vibro continue --json``; named with a
    trailing underscore because ``continue`` is a Python keyword). The dict also holds ``table``, a
    structured array (value, sticking_fraction, stable) of the branch points, and ``loads``: each
    point's exact per-period contact loads (docs/loads.md) as arrays of shape (points, contacts),
    one per name of :data:`LOAD_FIELDS` (NaN: unknown; each point's ``loads_note`` says why), and
    ``strobe``, shape (points, contacts): each contact's coordinate at the forcing phase of the
    start, t ≡ initial.time (mod the orbit's period), as a sweep's ``x_B`` (docs/output.md). A
    scene with a compliant stop also has ``contact_phases``: ``peak_force`` and ``duration`` of
    shape (points, contacts), the largest certified peak force and the longest duration of each
    contact's phases over the orbit's period, ``phases`` their number, and ``rigid_distance``, the
    rigid model's orbit's largest distance from the point's (each point's own ``contact_phases``
    list holds every phase, as :func:`orbit` gives them; docs/compliant.md). With
    several contacts each point has its contact ``sequence`` and each bifurcation the ``contact``
    where it happens.

    ``from_=FILE, point=K`` restarts from point K of a branch stored with ``out`` (``--from``,
    ``--point``); ``switch=True`` follows instead the other branch through the branch-point or flip
    next to that point (the period-doubled branch at a flip), the half heading for ``to``, and at a
    pitchfork whose two halves both do, the one on ``side`` ("above" or "below") of the old branch
    (docs/orbits.md, "Branch switching")."""
    if (from_ is None) != (point is None):
        raise ValueError("from_ and point go together: the stored branch and the point K to start from")
    if switch not in (True, False) or (switch and from_ is None):
        raise ValueError(f"switch {switch!r}: True (with from_ and point) or False")
    if side not in ("above", "below"):
        raise ValueError(f"side {side!r}: expected 'above' or 'below'")
    _invoke("continue", scene, param=param, to=to, step=step, max_points=max_points, period=period, kind=kind,
            out=out, force=force, **({"from_": str(from_), "point": point, "switch": switch, "side": side}
                                     if from_ is not None else {}))
    text, interrupted = _vibro.continue_branch(_scene(scene), param, _float("to", to), _float("step", step),
                                               _int("max_points", max_points), _int("period", period), kind,
                                               _out(out), _main_thread(), "" if from_ is None else _path("from_", from_),
                                               -1 if point is None else _int("point", point),
                                               side if switch else "")
    if interrupted:
        raise _interrupted("continuation", out)
    d = _json.loads(text)
    d["table"] = _branch_table(d.get("points", []))
    d["loads"] = _loads_arrays(d.get("points", []))
    d["strobe"] = _strobe_array(d.get("points", []))
    phases = _contact_phase_arrays(d.get("points", []))
    if phases is not None:
        d["contact_phases"] = phases
    return d


# The defaults of `diagram`, from the library (include/vibro/diagram.hpp, DiagramDefaults): the
# same as `vibro diagram`'s, set in one place.
_DIAGRAM = _vibro.diagram_defaults()


def diagram(scene, param, from_, to, steps=_DIAGRAM["steps"], record=_DIAGRAM["record"],
            searches=_DIAGRAM["searches"], grid=_DIAGRAM["grid"], max_period=_DIAGRAM["max_period"],
            max_branches=_DIAGRAM["max_branches"], max_points=_DIAGRAM["max_points"],
            coverage_tolerance=_DIAGRAM["coverage_tolerance"], threads=_DIAGRAM["threads"], out=None, force=False):
    """The whole one-parameter bifurcation diagram of ``param`` over [``from_``, ``to``] (``vibro
    diagram --json``, docs/diagram.md): a sweep up and down and ``searches`` attractor searches
    seed continuations both ways (every periodic attractor, whatever its period); every branch
    point and flip is switched at (periods up to ``max_period``); a branch reached twice is kept
    once; every attractor of the sweep and the searches is checked to lie on a stable branch
    (within ``coverage_tolerance``) or reported uncovered with the reason; ``uncovered_windows``
    groups the uncovered not-periodic ones into windows of consecutive sweep values (``from``,
    ``to``, ``source``, ``count``, ``reason``). ``max_branches`` is a hard bound that keeps
    room for the seeds' branches before switched ones (docs/diagram.md, "The cap on branches");
    ``cap_reached``, ``seeds_left_out`` and ``switches_left_out`` say what it left out (each named
    in ``notes``). The defaults are
    ``vibro diagram``'s (docs/diagram.md).

    Each entry of ``branches`` holds the branch as :func:`continue_` gives it (``points``,
    ``bifurcations``, ``end``), how it was found (``origin``: "seed", "branch-point" or "flip";
    ``parent``, ``born_at``), why each end stopped (``end_first``, ``end_last``: e.g. "grazing (the
    orbit does not go on)"), and numpy arrays: ``value``, ``stable`` (bool), ``strobe`` (points,
    contacts: each contact's coordinate at t ≡ initial.time mod the period, the sweep's
    observable), ``max_multiplier``, ``sticking_fraction`` and ``table`` (structured). ``coverage``
    lists every attractor with the branch that holds it (None: uncovered, with ``reason``);
    ``sweep_value`` and ``sweep_x_B`` are the sweep's stroboscopic points as arrays."""
    _invoke("diagram", scene, param=param, from_=from_, to=to, steps=steps, record=record, searches=searches,
            grid=grid, max_period=max_period, max_branches=max_branches, max_points=max_points,
            coverage_tolerance=coverage_tolerance, threads=threads, out=out, force=force)
    text, interrupted = _vibro.diagram(_scene(scene), param, _float("from_", from_), _float("to", to),
                                       _int("steps", steps), _int("record", record), _int("searches", searches),
                                       _int("grid", grid), _int("max_period", max_period),
                                       _int("max_branches", max_branches), _int("max_points", max_points),
                                       _float("coverage_tolerance", coverage_tolerance), _int("threads", threads),
                                       _out(out), _main_thread())
    if interrupted:
        raise _interrupted("diagram", out)
    d = _json.loads(text)
    for b in d["branches"]:
        pts = b.get("points", [])
        b["value"] = _np.array([p["value"] for p in pts], dtype=float)
        b["stable"] = _np.array([bool(p["stable"]) for p in pts], dtype=bool)
        b["strobe"] = _strobe_array(pts)
        b["max_multiplier"] = _np.array([max([abs(complex(*m)) for m in p.get("floquet_multipliers") or []] or [_np.nan])
                                         for p in pts], dtype=float)
        b["table"] = _branch_table(pts)
        b["sticking_fraction"] = b["table"]["sticking_fraction"]
    sw = d.get("sweep", [])
    d["sweep_value"] = _np.array([p["value"] for p in sw for _ in p.get("x_B", [])], dtype=float)
    d["sweep_x_B"] = _np.array([x for p in sw for x in p.get("x_B", [])], dtype=float)
    return d


def _study(scene, basin, x, y, x_range, y_range, grid, samples, seed, threads, full_periods, out, force=False,
           resume=False, progress=None):
    _invoke("basin" if basin else "attractors", scene, x=x, y=y, x_range=x_range, y_range=y_range,
            **({"grid": tuple(grid), "out": out, "force": force} if basin else {"samples": samples, "seed": seed}),
            threads=threads, full_periods=full_periods, **({"resume": True} if resume else {}))
    if _np.ndim(grid) != 1:
        raise ValueError(f"grid {grid!r}: expected (NX, NY)")
    if not isinstance(resume, (bool, _np.bool_)):
        raise ValueError(f"resume {resume!r}: expected True or False, got {type(resume).__name__}")
    args = (_scene(scene), basin, x, y, [_float("x_range", v) for v in (x_range or [])],
            [_float("y_range", v) for v in (y_range or [])], [_int("grid", n) for n in grid],
            _int("samples", samples), _seed(seed), _int("threads", threads), bool(full_periods), _out(out),
            bool(resume))
    r = _with_progress(progress, "basin" if basin else "attractors", "cell",
                       lambda report: _vibro.study(*args, report, _main_thread()))
    if r["interrupted"]:
        raise _interrupted("basin study" if basin else "attractor study", out)
    d = _json.loads(r["json"])
    return d, r


def attractors(scene, x="x_B", y="v_B", x_range=None, y_range=None, samples=200, seed=1, threads=0,
               full_periods=False, progress=None):
    """Coexisting attractors from random initial states (``vibro attractors --json``). ``progress``:
    True for a progress bar, or a callable ``progress(done, total)`` (cells), as for :func:`simulate`."""
    d, _ = _study(scene, False, x, y, x_range, y_range, (1, 1), samples, seed, threads, full_periods, None,
                  progress=progress)
    return d


def basin(scene, x="x_B", y="v_B", x_range=None, y_range=None, grid=(64, 64), threads=0,
          full_periods=False, out=None, force=False, resume=False, progress=None):
    """Basins of attraction over two initial-state coordinates (``vibro basin --json``).

    Besides the keys of the JSON, the dict holds ``labels`` (ny, nx) int32: the attractor index of
    each cell (−1 unresolved, −2 inadmissible, −3 not computed), and ``x``, ``y``: the cell
    centres (nx,) and (ny,), and ``extent`` = (x_from, x_to, y_from, y_to) for ``imshow``.
    ``resume=True`` computes only the cells missing from the interrupted study in ``out``
    (``--resume``). ``progress``: True for a progress bar, or a callable ``progress(done, total)``
    (cells computed by this call), as for :func:`simulate`.
    """
    d, r = _study(scene, True, x, y, x_range, y_range, grid, 1, 1, threads, full_periods, out, force, resume,
                  progress)
    nx, ny = r["nx"], r["ny"]
    d["labels"] = _np.asarray(r["labels"], dtype=_np.int32).reshape(ny, nx)
    d["x"] = _np.asarray(r["x"])[:nx]
    d["y"] = _np.asarray(r["y"])[::nx]
    d["extent"] = tuple(r["x_range"]) + tuple(r["y_range"])
    return d


def sweep(scene, param, from_, to, steps=50, record=16, one_way=False, out=None, force=False, progress=None):
    """Brute-force bifurcation diagram by simulation, up then down (``vibro sweep --json``).
    ``progress``: True for a progress bar, or a callable ``progress(done, total)`` (runs), as for
    :func:`simulate`."""
    _invoke("sweep", scene, param=param, from_=from_, to=to, steps=steps, record=record, one_way=one_way,
            out=out, force=force)
    args = (_scene(scene), param, _float("from_", from_), _float("to", to), _int("steps", steps),
            _int("record", record), bool(one_way), _out(out))
    text, interrupted = _with_progress(progress, "sweep", "run", lambda report: _vibro.sweep(*args, report,
                                                                                            _main_thread()))
    if interrupted:
        raise _interrupted("sweep", out)
    return _json.loads(text)


def check(scene):
    """Cross-checks the exact engine, CVODE and the Poincaré solver (``vibro check --json``)."""
    text, interrupted = _vibro.check(_scene(scene), _main_thread())
    if interrupted:
        raise _interrupted("cross-check", None)
    return _json.loads(text)


def info(path):
    """What a vibro HDF5 file holds (``vibro info --json``)."""
    return _json.loads(_vibro.info(_path("path", path)))


def _records(rows, fields):
    """A structured array from a list of dicts: fields (name, dtype, null) in order, None → null."""
    a = _np.empty(len(rows), dtype=[(name, dtype) for name, dtype, _ in fields])
    for i, r in enumerate(rows):
        a[i] = tuple(null if r.get(name) is None else r[name] for name, _, null in fields)
    return a


def _text_width(rows, name):
    return "U%d" % max([1] + [len(r.get(name) or "") for r in rows])


_TABLE_TYPES = ("a file name (str or os.PathLike), a numpy structured array, a dict of 1-D arrays, a 2-D array "
                "with columns=[...], or a pandas DataFrame")


def _columns(name, table, columns):
    """A table given as arrays: a dict column name → 1-D numpy array (None for a file name).

    Accepted: a numpy structured array (a field of shape (n,), such as ``displacement``, gives the
    columns ``displacement_1..n``), a mapping of names to 1-D arrays, a 2-D array with ``columns``
    naming its columns, or a DataFrame-like object (``.columns`` and ``.to_numpy()``)."""
    if isinstance(table, (str, _os.PathLike)):
        if columns is not None:
            raise ValueError(f"columns: only for a 2-D array {name}, not a file name")
        return None
    plain = isinstance(table, (list, tuple)) or (isinstance(table, _np.ndarray) and table.dtype.names is None)
    if columns is not None and not plain:
        raise ValueError(f"columns: only for a 2-D array {name}; a {type(table).__name__} names its own columns")
    if isinstance(table, _np.ndarray) and table.dtype.names is not None:
        if table.ndim != 1:
            raise ValueError(f"{name}: expected a 1-D structured array, got shape {table.shape}")
        d = {}
        for field in table.dtype.names:
            a = table[field]
            if a.ndim == 2:
                for i in range(a.shape[1]):
                    d[f"{field}_{i + 1}"] = a[:, i]
            else:
                d[field] = a
    elif isinstance(table, _Mapping):
        d = {str(k): _np.asarray(v) for k, v in table.items()}
    elif hasattr(table, "columns") and hasattr(table, "to_numpy"):
        d = {str(c): _np.asarray(table[c].to_numpy()) for c in table.columns}
    elif isinstance(table, (_np.ndarray, list, tuple)):
        a = _np.asarray(table)
        if a.ndim != 2:
            raise ValueError(f"{name}: expected {_TABLE_TYPES}; got an array of shape {a.shape}")
        if columns is None or len(columns) != a.shape[1]:
            raise ValueError(f"{name}: a 2-D array of {a.shape[1]} columns needs their names: columns=[...] "
                             f"with {a.shape[1]} names" + ("" if columns is None else f" (got {len(columns)})"))
        d = {str(c): a[:, j] for j, c in enumerate(columns)}
    else:
        raise ValueError(f"{name}: expected {_TABLE_TYPES}; got {type(table).__name__}")
    for k, v in d.items():
        if v.ndim != 1:
            raise ValueError(f"{name} column {k!r}: expected a 1-D array, got shape {v.shape}")
    return d


def _numbers(name, column, values):
    """A numeric column as float64 (booleans as 0/1)."""
    if values.dtype.kind not in "biuf":
        raise ValueError(f"{name} column {column!r}: expected numbers, got an array of dtype {values.dtype}")
    return values.astype(_np.float64)


def _shown(table):
    """How a table argument is recorded in a file's provenance: its file name, or what it was."""
    if isinstance(table, (str, _os.PathLike)):
        return str(table)
    return f"<{type(table).__name__} of {len(table) if hasattr(table, '__len__') else '?'} rows>"


def _sequences(values):
    """The claimed contact sequences of a branch table as text ("" where a row makes no claim: an
    empty string, None or NaN)."""
    if values.dtype.kind not in "USO":
        raise ValueError(f"branch column 'sequence': expected strings (a contact sequence such as "
                         f"'0:impact 1:impact'), got an array of dtype {values.dtype}")
    out = []
    for i, v in enumerate(values):
        if v is None or (isinstance(v, float) and _math.isnan(v)):
            out.append("")
        elif isinstance(v, (str, bytes, _np.str_, _np.bytes_)):
            out.append((v.decode() if isinstance(v, bytes) else str(v)).strip())
        else:
            raise ValueError(f"branch row {i} (sequence): expected a string, got {type(v).__name__}")
    return out


def validate(scene, branch, param, kind="auto", period=0, tolerance=1e-6, sticking_tolerance=1e-6, out=None,
             force=False, columns=None, progress=None):
    """Confirms or refutes, point by point, a branch of periodic orbits computed by another tool
    (``vibro validate --json``). ``branch`` is the CSV file, or the same table as arrays (a numpy
    structured array, a dict of 1-D arrays, a 2-D array with ``columns=[...]``, a DataFrame), with
    the columns value, time, displacement_1..n, velocity_1..n (or fields ``displacement`` and
    ``velocity`` of shape (n,)) and optionally period, stable, sticking_fraction (NaN: no claim) and,
    for a scene with several contacts, sequence (strings, the orbit's contact sequence as
    ``orbit(...)["sequence"]`` writes it; "" or None: no claim); ``param`` is the scene key its
    value column sets. Besides the keys of the JSON, the dict holds
    ``table``: a structured array with one row per point (value, verdict, distance, period (−1:
    none), stable (−1: none), sticking_fraction, simulated_distance; NaN for null floats).
    ``progress``: True for a progress bar, or a callable ``progress(done, total)`` (points), as for
    :func:`simulate`."""
    _invoke("validate", scene, branch=_shown(branch), param=param, kind=kind, period=period, tolerance=tolerance,
            sticking_tolerance=sticking_tolerance, out=out, force=force)
    cols = _columns("branch", branch, columns)
    sequences = None
    if cols is not None:
        if "sequence" in cols:
            sequences = _sequences(cols.pop("sequence"))
        cols = {k: _numbers("branch", k, v) for k, v in cols.items()}
    args = (_scene(scene), "" if cols is not None else _path("branch", branch), cols, sequences, param, kind,
            _int("period", period), _float("tolerance", tolerance), _float("sticking_tolerance", sticking_tolerance),
            _out(out))
    text, interrupted = _with_progress(progress, "validate", "point",
                                       lambda report: _vibro.validate(*args, report, _main_thread()))
    if interrupted:
        raise _interrupted("validation", out)
    d = _json.loads(text)
    points = d["points"]
    d["table"] = _records(points, [("value", "f8", _np.nan), ("verdict", _text_width(points, "verdict"), ""),
                                   ("distance", "f8", _np.nan), ("period", "i4", -1), ("stable", "i1", -1),
                                   ("sticking_fraction", "f8", _np.nan), ("simulated_distance", "f8", _np.nan)])
    return d


def _event_columns(cols):
    """t, kind (as text: a name or its number 1..5), velocity and contact (or None) of an events
    table given as arrays. vibro's own events (:attr:`SimulationResult.events`) are taken as they
    are: their ``v_before`` is the velocity just before the event, and their ``contact`` (when
    present) the event's contact."""
    names = set(cols)
    own = {"t", "kind", "x_B", "v_before", "v_after"}
    extra = {"contact", "simultaneous", "impulse", "energy_dissipated", "stick_duration", "reaction_integral",
             "reaction_max", "peak_time", "penetration_max"}
    if own <= names <= own | extra:  # vibro's own events (a run or a file, with or without the loads)
        cols = {"t": cols["t"], "kind": cols["kind"], "velocity": cols["v_before"],
                **({"contact": cols["contact"]} if "contact" in cols else {})}
        names = set(cols)
    for k in sorted(names - {"t", "kind", "velocity", "contact"}):
        raise ValueError(f"events: unknown column {k!r} (expected t, kind and optionally velocity, contact)")
    for k in ("t", "kind"):
        if k not in names:
            raise ValueError(f"events: missing column {k!r} (expected t, kind and optionally velocity)")
    kind = cols["kind"]
    if kind.dtype.kind in "biuf":
        kinds = [str(int(k)) if _math.isfinite(k) and float(k).is_integer() else repr(float(k)) for k in kind]
    elif kind.dtype.kind in "USO":
        kinds = [k.decode() if isinstance(k, bytes) else str(k) for k in kind]
    else:
        raise ValueError(f"events column 'kind': expected names or numbers 1..5, got an array of dtype {kind.dtype}")
    velocity = _numbers("events", "velocity", cols["velocity"]) if "velocity" in cols else None
    contact = _numbers("events", "contact", cols["contact"]) if "contact" in cols else None
    return _numbers("events", "t", cols["t"]), kinds, velocity, contact


def score(scene, events, window=0.05, tolerance=1e-6, columns=None):
    """Scores another simulator's events against vibro's run of the scene (``vibro score --json``).
    ``events`` is the CSV file (t, kind[, velocity]), or the same table as arrays (a numpy
    structured array, a dict of 1-D arrays, a 2-D array with ``columns=[...]``, a DataFrame; kind as
    names or as the numbers of :data:`EVENT_KINDS`; velocity NaN: not given; with several contacts
    optionally contact, each event's contact, on every row or none), or vibro's own
    ``simulate(...).events`` (with their contacts). Besides the keys of the JSON, the dict holds
    ``table``: a structured array with one row per event kind (kind, theirs, ours, matched,
    in_accumulation, max_time_error, mean_time_error, max_velocity_error (NaN: none)), and
    ``vibro_run``: the status and message of vibro's own run ("ok" unless it stopped early, when
    the command line exits 3)."""
    _invoke("score", scene, events=_shown(events), window=window, tolerance=tolerance)
    cols = _columns("events", events, columns)
    t, kinds, velocity, contact = _event_columns(cols) if cols is not None else (None, [], None, None)
    text, interrupted, status, message = _vibro.score(_scene(scene), "" if cols is not None else _path("events", events),
                                                      t, kinds, velocity, contact, _float("window", window),
                                                      _float("tolerance", tolerance), _main_thread())
    if interrupted:
        raise _interrupted("scoring run", None)
    d = _json.loads(text)
    kinds = d["kinds"]
    d["table"] = _records(kinds, [("kind", _text_width(kinds, "kind"), ""), ("theirs", "i8", 0), ("ours", "i8", 0),
                                  ("matched", "i8", 0), ("in_accumulation", "i8", 0),
                                  ("max_time_error", "f8", _np.nan), ("mean_time_error", "f8", _np.nan),
                                  ("max_velocity_error", "f8", _np.nan)])
    d["vibro_run"] = {"status": status, "message": message}
    return d


def partition(scene, params, range1, range2, sticking_fraction, steps1=20, from2=None, period=0, threads=0,
              out=None, force=False):
    """Curves of constant sticking fraction in the plane of two scene keys, and the existence
    boundaries of the sticking orbits (``vibro partition --json``). ``params`` = (KEY1, KEY2);
    ``range1`` = (A, B) is split in ``steps1`` steps, each column being continued in KEY2 over
    ``range2`` = (C, D) from ``from2`` (default: the scene's KEY2); ``sticking_fraction`` lists the
    levels to trace. Besides the keys of the JSON, the dict holds ``crossings`` (value1, level,
    value2) and ``boundaries`` (value1, kind, value2): structured arrays, one row per point;
    ``cells`` (value1, value2, sticking_fraction, stable), every branch point of every column; and
    ``loads``, the cells' exact per-period contact loads (docs/loads.md) as arrays of shape
    (cells, contacts), one per name of :data:`LOAD_FIELDS` (NaN: unknown); ``sequences`` (value1,
    from, to, sequence: with several contacts, the spans of KEY2 with one contact sequence; no rows
    for one contact)."""
    levels = [float(s) for s in (sticking_fraction if _np.ndim(sticking_fraction) else [sticking_fraction])]
    _invoke("partition", scene, params=tuple(params), range1=tuple(range1), range2=tuple(range2),
            sticking_fraction=tuple(levels), steps1=steps1, from2=from2, period=period, threads=threads, out=out,
            force=force)
    text, interrupted = _vibro.partition(_scene(scene), [str(p) for p in params],
                                         [_float("range1", v) for v in range1], [_float("range2", v) for v in range2],
                                         levels, _int("steps1", steps1), None if from2 is None else _float("from2", from2),
                                         _int("period", period), _int("threads", threads), _out(out), _main_thread())
    if interrupted:
        raise _interrupted("partition", out)
    d = _json.loads(text)
    crossings = [{"value1": c["value1"], "level": x["level"], "value2": x["value"]}
                 for c in d["columns"] for x in c["crossings"]]
    boundaries = [{"value1": c["value1"], "kind": b["kind"], "value2": b["value"]}
                  for c in d["columns"] for b in c["bifurcations"]]
    d["crossings"] = _records(crossings, [("value1", "f8", _np.nan), ("level", "f8", _np.nan),
                                          ("value2", "f8", _np.nan)])
    d["boundaries"] = _records(boundaries, [("value1", "f8", _np.nan), ("kind", _text_width(boundaries, "kind"), ""),
                                            ("value2", "f8", _np.nan)])
    cells = [dict(p, value1=c["value1"]) for c in d["columns"] for p in c.get("points", [])]
    d["cells"] = _records(cells, [("value1", "f8", _np.nan), ("value2", "f8", _np.nan),
                                  ("sticking_fraction", "f8", _np.nan), ("stable", "?", False)])
    d["loads"] = _loads_arrays(cells)
    spans = [{"value1": c["value1"], "from": sp["from"], "to": sp["to"], "sequence": sp["sequence"]}
             for c in d["columns"] for sp in c.get("sequences", [])]
    d["sequences"] = _records(spans, [("value1", "f8", _np.nan), ("from", "f8", _np.nan), ("to", "f8", _np.nan),
                                      ("sequence", _text_width(spans, "sequence"), "")])
    return d


def curve(scene, params, range1, range2, kind=None, toward=None, from_=None, point=None, contact=-1, step=0.02,
          max_step=0.1, max_points=200, period=0, transient=200, orbit="auto", out=None, force=False):
    """Curves of codimension-one bifurcations in the plane of two scene keys (``vibro curve --json``,
    docs/diagram.md "Two-parameter curves"). ``params`` = (KEY1, KEY2); the curves stay in the box
    ``range1`` x ``range2``. ``kind``: one kind or a list ("fold", "flip", "neimark-sacker",
    "branch-point", "grazing", "sticking-lost", "sticking-entry", "rising", "simultaneous"). The start:
    ``toward=(A, B)``, the first such bifurcation met from the scene's (KEY1, KEY2) towards (A, B), or
    ``from_=BRANCH.h5, point=K``, bifurcation K of a branch stored by :func:`continue_` (``kind``
    defaults to its kind). ``contact``: with several contacts, follow a non-smooth kind on that contact.
    ``orbit``: with ``toward``, the kind of the start orbit ("auto", "sticking", "impact").

    Returns a list, one dict per kind: the keys of the JSON (kind, contact, period, status,
    end_start, end_finish, points, special) and numpy arrays ``value1``, ``value2`` (the curve in
    order), ``bracket``, ``stable``, ``max_multiplier``, and ``special`` as a structured array
    (kind, value1, value2, bracket, after, detail): the codimension-two points."""
    kinds = [] if kind is None else ([kind] if isinstance(kind, str) else [str(k) for k in kind])
    if (from_ is None) != (point is None):
        raise ValueError("from_ and point go together: the stored branch and its bifurcation K")
    _invoke("curve", scene, params=tuple(params), range1=tuple(range1), range2=tuple(range2), kind=tuple(kinds),
            toward=None if toward is None else tuple(toward), from_=None if from_ is None else str(from_),
            point=point, contact=contact, step=step, max_step=max_step, max_points=max_points, period=period,
            transient=transient, orbit=orbit, out=out, force=force)
    text, interrupted = _vibro.curve(_scene(scene), [str(p) for p in params], [_float("range1", v) for v in range1],
                                     [_float("range2", v) for v in range2], kinds,
                                     [] if toward is None else [_float("toward", v) for v in toward],
                                     "" if from_ is None else _path("from_", from_),
                                     -1 if point is None else _int("point", point), _int("contact", contact),
                                     _float("step", step), _float("max_step", max_step), _int("max_points", max_points),
                                     _int("period", period), _int("transient", transient), str(orbit), _out(out),
                                     _main_thread())
    if interrupted:
        raise _interrupted("curve", out)
    curves = _json.loads(text)["curves"]
    for c in curves:
        pts = c["points"]
        c["value1"] = _np.array([p["value1"] for p in pts], dtype=float)
        c["value2"] = _np.array([p["value2"] for p in pts], dtype=float)
        c["bracket"] = _np.array([p["bracket"] for p in pts], dtype=float)
        c["stable"] = _np.array([p["stable"] for p in pts], dtype=bool)
        c["max_multiplier"] = _np.array([_np.nan if p["max_multiplier"] is None else p["max_multiplier"] for p in pts],
                                        dtype=float)
        sp = c["special"]
        c["special"] = _records(sp, [("kind", _text_width(sp, "kind"), ""), ("value1", "f8", _np.nan),
                                     ("value2", "f8", _np.nan), ("bracket", "f8", _np.nan), ("after", "i8", -1),
                                     ("detail", _text_width(sp, "detail"), "")])
    return curves


class Group(dict):
    """A group of a vibro HDF5 file read into memory by :func:`read`: datasets as numpy arrays
    (string datasets as arrays of ``str``), subgroups as ``Group``; ``attrs`` holds the attributes
    (strings as ``str``, string arrays as lists of ``str``, scalars as Python numbers)."""

    def __init__(self, name, items, attrs):
        super().__init__(items)
        self.name, self.attrs = name, attrs

    def __repr__(self):
        return f"vibro.Group({self.name!r}, {sorted(self)}, attrs={sorted(self.attrs)})"


def _attr_value(v):
    if isinstance(v, bytes):
        return v.decode("utf-8")
    if isinstance(v, _np.ndarray) and v.dtype.kind in "OS":
        return [x.decode("utf-8") if isinstance(x, bytes) else str(x) for x in v.ravel()]
    if isinstance(v, _np.generic):
        return v.item()
    return v


def _dataset_value(d):
    import h5py
    if h5py.check_string_dtype(d.dtype) is not None:
        # h5py 3 reads variable-length strings as bytes; .asstr() decodes them (UTF-8).
        return _np.array(d.asstr()[()], dtype=str).reshape(d.shape)
    return d[()]


def read(path):
    """Reads a whole vibro HDF5 file (docs/output.md) into memory with h5py: a :class:`Group` of the
    root, e.g. ``read("run.h5")["events"]["t"]``, ``read("b.h5")["branch"]["events"]`` (an array of
    ``str``, where h5py alone gives ``bytes``) and ``read("run.h5").attrs["scene"]``. Meant for the
    result groups (branches, studies, sweeps, orbits); for long runs read ``/samples`` with h5py
    directly, slice by slice. A file that is not a readable vibro file raises ValueError, as
    ``vibro info`` refuses it (its test read runs first, in a child process)."""
    import h5py

    info(path)

    def group(g):
        items = {}
        for k, v in g.items():
            items[k] = group(v) if isinstance(v, h5py.Group) else _dataset_value(v)
        return Group(g.name, items, {k: _attr_value(v) for k, v in g.attrs.items()})

    with h5py.File(str(path), "r") as f:
        return group(f)
