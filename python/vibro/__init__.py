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
import threading as _threading

import numpy as _np

from . import _vibro

__version__ = _vibro.version
git_commit = _vibro.git_commit

#: Event kinds as stored in ``events["kind"]`` and in HDF5 files (the enum of /events/kind).
EVENT_KINDS = {1: "impact", 2: "accumulation", 3: "stick", 4: "release", 5: "grazing"}
#: Motion modes of ``samples["mode"]``: 0 free flight, 1 sticking.
MODES = {0: "free", 1: "sticking"}

__all__ = ["Scene", "SimulationResult", "Group", "load_scene", "model", "simulate", "orbit", "continue_",
           "attractors", "basin", "sweep", "check", "info", "validate", "score", "partition", "read",
           "EVENT_KINDS", "MODES"]


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
    return Scene(_vibro.load_scene(str(path), _overrides(set)))


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


def _interrupted(what, out):
    kept = f"; {out} keeps everything computed so far" if out else ""
    return KeyboardInterrupt(f"vibro: {what} interrupted{kept}")


def model(scene):
    """The model as vibro understands the scene (the dict of ``vibro model --json``)."""
    return _json.loads(_vibro.model(_scene(scene)))


def _events_array(e):
    a = _np.empty(len(e["t"]), dtype=[("t", "f8"), ("kind", "i1"), ("x_B", "f8"), ("v_before", "f8"),
                                      ("v_after", "f8")])
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
    - ``events``: structured array, fields t, kind (:data:`EVENT_KINDS`), x_B, v_before, v_after;
    - ``samples``: structured array of the dense output, fields t, X (n,), V (n,), x_B, mode;
    - ``section``: the stroboscopic section (t0 + kT), same fields as ``samples``.
    """

    def __init__(self, summary, events, samples, section):
        self.summary, self.events, self.samples, self.section = summary, events, samples, section

    def __repr__(self):
        a = self.summary.get("attractor", {})
        return (f"SimulationResult(status={self.summary.get('status')!r}, attractor={a.get('kind')!r}, "
                f"{len(self.events)} events, {len(self.samples)} samples)")


def simulate(scene, out=None, force=False):
    """Simulates the scene (``vibro simulate``); with ``out`` also writes the HDF5 file (``force``:
    replace a vibro file of another scene or command)."""
    _invoke("simulate", scene, out=out, force=force)
    r = _vibro.simulate(_scene(scene), str(out) if out else "", _main_thread())
    if r["interrupted"]:
        raise _interrupted("simulation", out)
    return SimulationResult(_json.loads(r["json"]), _events_array(r["events"]), _rows_array(r["samples"]),
                            _rows_array(r["section"]))


def orbit(scene, kind="auto", period=0, impacts=0, guess=None, out=None, force=False, transient=None):
    """Finds a periodic orbit with the Poincaré solver (``vibro orbit --json``). ``guess`` is the
    phase ωt of the release (or first impact), or (phase, contact velocity): Newton starts there
    unless ``transient`` periods are asked for. Without a guess, ``transient`` defaults to 200;
    ``transient=0`` starts Newton at the scene's initial state (``vibro orbit --transient 0``)."""
    if transient is None:
        transient = 0 if guess is not None else 200
    _invoke("orbit", scene, kind=kind, period=period, impacts=impacts, guess=guess, out=out, force=force,
            transient=transient)
    phase = velocity = None
    if guess is not None:
        if isinstance(guess, (tuple, list)):
            phase, velocity = (float(guess[0]), float(guess[1])) if len(guess) > 1 else (float(guess[0]), None)
        else:
            phase = float(guess)
    return _json.loads(_vibro.orbit(_scene(scene), kind, int(period), int(impacts), phase, velocity,
                                    str(out) if out else "", int(transient)))


def _branch_table(points):
    t = _np.empty(len(points), dtype=[("value", "f8"), ("sticking_fraction", "f8"), ("stable", "?")])
    for i, p in enumerate(points):
        sf = p.get("sticking_fraction")
        t[i] = (p["value"], _np.nan if sf is None else sf, bool(p["stable"]))
    return t


def continue_(scene, param, to, step=0.0, max_points=1000, period=0, kind="auto", out=None, force=False):
    """Continues a periodic orbit in ``param`` up to ``to`` (``vibro continue --json``; named with a
    trailing underscore because ``continue`` is a Python keyword). The dict also holds ``table``, a
    structured array (value, sticking_fraction, stable) of the branch points."""
    _invoke("continue", scene, param=param, to=to, step=step, max_points=max_points, period=period, kind=kind,
            out=out, force=force)
    text, interrupted = _vibro.continue_branch(_scene(scene), param, float(to), float(step),
                                               int(max_points), int(period), kind,
                                               str(out) if out else "", _main_thread())
    if interrupted:
        raise _interrupted("continuation", out)
    d = _json.loads(text)
    d["table"] = _branch_table(d.get("points", []))
    return d


def _study(scene, basin, x, y, x_range, y_range, grid, samples, seed, threads, full_periods, out, force=False):
    _invoke("basin" if basin else "attractors", scene, x=x, y=y, x_range=x_range, y_range=y_range,
            **({"grid": tuple(grid), "out": out, "force": force} if basin else {"samples": samples, "seed": seed}),
            threads=threads, full_periods=full_periods)
    r = _vibro.study(_scene(scene), basin, x, y, list(x_range or []), list(y_range or []),
                     list(grid), int(samples), int(seed), int(threads), bool(full_periods),
                     str(out) if out else "", _main_thread())
    if r["interrupted"]:
        raise _interrupted("basin study" if basin else "attractor study", out)
    d = _json.loads(r["json"])
    return d, r


def attractors(scene, x="x_B", y="v_B", x_range=None, y_range=None, samples=200, seed=1, threads=0,
               full_periods=False):
    """Coexisting attractors from random initial states (``vibro attractors --json``)."""
    d, _ = _study(scene, False, x, y, x_range, y_range, (1, 1), samples, seed, threads, full_periods, None)
    return d


def basin(scene, x="x_B", y="v_B", x_range=None, y_range=None, grid=(64, 64), threads=0,
          full_periods=False, out=None, force=False):
    """Basins of attraction over two initial-state coordinates (``vibro basin --json``).

    Besides the keys of the JSON, the dict holds ``labels`` (ny, nx) int32: the attractor index of
    each cell (−1 unresolved, −2 inadmissible, −3 not computed), and ``x``, ``y``: the cell
    centres (nx,) and (ny,), and ``extent`` = (x_from, x_to, y_from, y_to) for ``imshow``.
    """
    d, r = _study(scene, True, x, y, x_range, y_range, grid, 1, 1, threads, full_periods, out, force)
    nx, ny = r["nx"], r["ny"]
    d["labels"] = _np.asarray(r["labels"], dtype=_np.int32).reshape(ny, nx)
    d["x"] = _np.asarray(r["x"])[:nx]
    d["y"] = _np.asarray(r["y"])[::nx]
    d["extent"] = tuple(r["x_range"]) + tuple(r["y_range"])
    return d


def sweep(scene, param, from_, to, steps=50, record=16, one_way=False, out=None, force=False):
    """Brute-force bifurcation diagram by simulation, up then down (``vibro sweep --json``)."""
    _invoke("sweep", scene, param=param, from_=from_, to=to, steps=steps, record=record, one_way=one_way,
            out=out, force=force)
    text, interrupted = _vibro.sweep(_scene(scene), param, float(from_), float(to), int(steps),
                                     int(record), bool(one_way), str(out) if out else "", _main_thread())
    if interrupted:
        raise _interrupted("sweep", out)
    return _json.loads(text)


def check(scene):
    """Cross-checks the exact engine, CVODE and the Poincaré solver (``vibro check --json``)."""
    return _json.loads(_vibro.check(_scene(scene)))


def info(path):
    """What a vibro HDF5 file holds (``vibro info --json``)."""
    return _json.loads(_vibro.info(str(path)))


def _records(rows, fields):
    """A structured array from a list of dicts: fields (name, dtype, null) in order, None → null."""
    a = _np.empty(len(rows), dtype=[(name, dtype) for name, dtype, _ in fields])
    for i, r in enumerate(rows):
        a[i] = tuple(null if r.get(name) is None else r[name] for name, _, null in fields)
    return a


def _text_width(rows, name):
    return "U%d" % max([1] + [len(r.get(name) or "") for r in rows])


def validate(scene, branch, param, kind="auto", period=0, tolerance=1e-6, sticking_tolerance=1e-6, out=None,
             force=False):
    """Confirms or refutes, point by point, a branch of periodic orbits computed by another tool
    (``vibro validate --json``). ``branch`` is the CSV file (value, time, displacement_1..n,
    velocity_1..n[, period, stable, sticking_fraction]) and ``param`` the scene key its value column
    sets. Besides the keys of the JSON, the dict holds ``table``: a structured array with one row per
    point (value, verdict, distance, period (−1: none), stable (−1: none), sticking_fraction,
    simulated_distance; NaN for null floats)."""
    _invoke("validate", scene, branch=str(branch), param=param, kind=kind, period=period, tolerance=tolerance,
            sticking_tolerance=sticking_tolerance, out=out, force=force)
    text, interrupted = _vibro.validate(_scene(scene), str(branch), param, kind, int(period), float(tolerance),
                                        float(sticking_tolerance), str(out) if out else "", _main_thread())
    if interrupted:
        raise _interrupted("validation", out)
    d = _json.loads(text)
    points = d["points"]
    d["table"] = _records(points, [("value", "f8", _np.nan), ("verdict", _text_width(points, "verdict"), ""),
                                   ("distance", "f8", _np.nan), ("period", "i4", -1), ("stable", "i1", -1),
                                   ("sticking_fraction", "f8", _np.nan), ("simulated_distance", "f8", _np.nan)])
    return d


def score(scene, events, window=0.05, tolerance=1e-6):
    """Scores another simulator's events against vibro's run of the scene (``vibro score --json``).
    ``events`` is the CSV file (t, kind[, velocity]). Besides the keys of the JSON, the dict holds
    ``table``: a structured array with one row per event kind (kind, theirs, ours, matched,
    in_accumulation, max_time_error, mean_time_error, max_velocity_error (NaN: none)), and
    ``vibro_run``: the status and message of vibro's own run ("ok" unless it stopped early, when
    the command line exits 3)."""
    _invoke("score", scene, events=str(events), window=window, tolerance=tolerance)
    text, interrupted, status, message = _vibro.score(_scene(scene), str(events), float(window), float(tolerance),
                                                      _main_thread())
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
    value2) and ``boundaries`` (value1, kind, value2): structured arrays, one row per point."""
    levels = [float(s) for s in (sticking_fraction if _np.ndim(sticking_fraction) else [sticking_fraction])]
    _invoke("partition", scene, params=tuple(params), range1=tuple(range1), range2=tuple(range2),
            sticking_fraction=tuple(levels), steps1=steps1, from2=from2, period=period, threads=threads, out=out,
            force=force)
    text, interrupted = _vibro.partition(_scene(scene), [str(p) for p in params], [float(v) for v in range1],
                                         [float(v) for v in range2], levels, int(steps1),
                                         None if from2 is None else float(from2), int(period), int(threads),
                                         str(out) if out else "", _main_thread())
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
    return d


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
    directly, slice by slice."""
    import h5py

    def group(g):
        items = {}
        for k, v in g.items():
            items[k] = group(v) if isinstance(v, h5py.Group) else _dataset_value(v)
        return Group(g.name, items, {k: _attr_value(v) for k, v in g.attrs.items()})

    with h5py.File(str(path), "r") as f:
        return group(f)
