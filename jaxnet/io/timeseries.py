"""Time series of a dynamic run, written record by record as the run goes, and resumable.

The dynamic solver hands a :class:`Record` (time, step, node positions and velocities, and the figures of
that instant) to a :class:`SeriesWriter` at each record time. The writer puts it on disk at once, so that a
run that is killed loses none of the records already written, and so that the run can be resumed from its
last record exactly: with each record the writer also keeps a *checkpoint* (the last record and whatever
arrays the solver needs to carry on bit for bit: previous positions, the current time step...).

Units are SI, as everywhere in jaxnet: s, m, m/s; a figure's unit is in its name ("reaction_N").

Layout of ``out_dir``::

    series.json          the index: arrays (name, raw file, shape of one record, dtype), the number of
                         complete records, the scene's counts, what the run says of itself ("run": the
                         time its waves and motions grew in over, ``start_ramp_s``). Replaced atomically.
    raw/<name>.bin       one append-only raw file per array: record after record, C order, little-endian
                         float64 (int64 for ``step`` and for integer figures). Figure ``f`` is in
                         ``raw/figure.f.bin``.
    checkpoint.npz       the last record and the solver's arrays. Replaced atomically.
    net_NNNNN.vtu        (``vtk=True``) the net at record NNNNN (:func:`write_vtu_state`): displacement, velocity
                         and reactions as point data, tensions and mesh opening angles as cell data.
    series.pvd           (``vtk=True``) ParaView collection of the .vtu files with their times.
    series.npz           written by ``close()``: time (R,), step (R,), position (R, N, 3), velocity (R, N, 3)
                         and every figure (R, ...), as :func:`read_series` returns them.

Why raw files plus an index rather than an .npz rewritten at each record: an .npz cannot be appended to,
so rewriting it at each of R records costs O(R²) bytes; a raw file grows by one fixed-size record and its
earlier bytes are never touched again, so a crash cannot damage them.

Order of the writes of one record, and why. A record is *complete* once the index counts it; readers
(:func:`read_series`, also of a run still going, possibly from another process) read that many records and
ignore any bytes beyond. The writer does, in this order:

  1. append the record to every raw file (and flush: another process sees it);
  2. write ``net_NNNNN.vtu`` (``vtk=True``), through a temporary file renamed into place;
  3. replace ``checkpoint.npz``: the record itself (all its arrays, figures included) and the solver's;
  4. replace ``series.json`` with the count raised by one;
  5. replace ``series.pvd`` (``vtk=True``).

The checkpoint is written *before* the index because the checkpoint holds only the latest state: a crash
between 3 and 4 leaves a checkpoint one record ahead of the index, and since the checkpoint holds that
whole record, resuming *rolls the index forward* (rewrites the record into the raw files from the
checkpoint, then counts it) and nothing is lost. The other order would leave, after a crash between the two
writes, an index one record ahead of a checkpoint that is the only state the solver could restart from;
consistent too, but it would drop a record. So at any time the checkpoint's count c and the index's r
satisfy r <= c <= r + 1, and :func:`resume_point` returns the checkpoint's record. A crash before 3 leaves
c = r and maybe a partial record in the raw files, which resuming truncates. Each replacement goes
through a temporary file in ``out_dir`` and ``os.replace`` (atomic on POSIX), so a reader never sees a
half-written index, checkpoint or .pvd. ``fsync=True`` also forces every write to the disk before the next
(durable against a power cut, not only a killed process; slower).

``Record.step`` and integer figures (``newton_iterations``) are stored as int64, everything else as
float64: a record is read back bit for bit. The figures' names, shapes and dtypes are fixed by the first
record; a later record that differs raises :class:`SeriesError` naming the figure, before anything of it
is written. Figure names are identifiers (letters, digits, underscores) because they name files.

"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
import re
import xml.sax.saxutils

import numpy as np

from jaxnet.io import vtk

INDEX = "series.json"
CHECKPOINT = "checkpoint.npz"
SERIES = "series.npz"
PVD = "series.pvd"
RAW = "raw"
FORMAT = "jaxnet time series"
VERSION = 1
#: arrays of every record, besides the figures; their names are reserved
BASE = ("time", "step", "position", "velocity")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_PARTIAL = ".partial"  # marks temporary files, removed when a series is opened


class SeriesError(ValueError):
    """A record that does not fit the series, or a series on disk that is inconsistent; the message says which."""


@dataclasses.dataclass(frozen=True, eq=False)
class Record:
    """The state of a dynamic run at one record time.

    time: simulated time (s). step: number of time steps taken so far. position, velocity: (N, 3) node
    positions (m) and velocities (m/s). figures: name -> float, int or array of a fixed shape (e.g.
    "reaction_N" (N, 3) forces (N) at fixed coordinates, "drag_netting_N" (3,), "volume_m3",
    "newton_iterations", "time_step_s"); the set of names, the shapes and int-or-float are fixed by the first
    record of a series.
    """

    time: float
    step: int
    position: np.ndarray
    velocity: np.ndarray
    figures: dict = dataclasses.field(default_factory=dict)


# --------------------------------------------------------------------------------------------------
# Files
# --------------------------------------------------------------------------------------------------


def _sync_dir(directory):
    """fsync a directory, so that a rename in it survives a power cut."""
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _replace(path, write, fsync=False):
    """Write ``path`` atomically: ``write(file)`` into a temporary file beside it, then ``os.replace``."""
    path = pathlib.Path(path)
    tmp = path.with_name(path.stem + _PARTIAL + path.suffix)
    with open(tmp, "wb") as f:
        write(f)
        f.flush()
        if fsync:
            os.fsync(f.fileno())
    os.replace(tmp, path)
    if fsync:
        _sync_dir(path.parent)


def _raw_file(name):
    return f"{RAW}/{name}.bin" if name in BASE else f"{RAW}/figure.{name}.bin"


def _record_bytes(shape, dtype):
    return int(np.prod(shape, dtype=np.int64)) * np.dtype(dtype).itemsize


def _read_index(out_dir):
    path = pathlib.Path(out_dir) / INDEX
    if not path.exists():
        return None
    index = json.loads(path.read_text())
    if index.get("format") != FORMAT or index.get("version") != VERSION:
        raise SeriesError(f"{path}: not a {FORMAT} of version {VERSION}")
    return index


def _read_raw(out_dir, entry, count):
    """The first ``count`` records of one array, (count, *shape); bytes beyond them (a record being
    written, or left half-written by a crash) are ignored."""
    path = pathlib.Path(out_dir) / entry["file"]
    shape, dtype = tuple(entry["shape"]), np.dtype(entry["dtype"])
    size = int(np.prod(shape, dtype=np.int64))
    data = np.fromfile(path, dtype=dtype, count=count * size) if count else np.zeros(0, dtype)
    if data.size != count * size:
        raise SeriesError(f"{path}: holds {data.size // max(size, 1)} records, the index counts {count}")
    return data.reshape((count, *shape))


def _read_checkpoint(out_dir):
    """(count, Record, solver arrays) of ``checkpoint.npz``, or None when there is none."""
    path = pathlib.Path(out_dir) / CHECKPOINT
    if not path.exists():
        return None
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    figures = {k[len("figure."):]: _unwrap(v) for k, v in arrays.items() if k.startswith("figure.")}
    solver = {k[len("solver."):]: v for k, v in arrays.items() if k.startswith("solver.")}
    record = Record(time=float(arrays["time"]), step=int(arrays["step"]), position=arrays["position"],
                    velocity=arrays["velocity"], figures=figures)
    return int(arrays["records"]), record, solver


def _unwrap(value):
    """A 0-d array back to the Python float or int it was given as; arrays as they are."""
    return value.item() if value.ndim == 0 else value


def _figure_array(name, value):
    """A figure as an int64 or float64 array (int64 for integers and booleans: iteration counts)."""
    arr = np.asarray(value)
    if arr.dtype.kind in "biu":
        return arr.astype("<i8")
    if arr.dtype.kind == "f":
        return arr.astype("<f8")
    raise SeriesError(f"figure {name!r}: values must be real numbers (float or int), got dtype {arr.dtype}")


# --------------------------------------------------------------------------------------------------
# VTK
# --------------------------------------------------------------------------------------------------


def write_vtu_state(path, scene, position, velocity=None, fsync=False, point_data=None):
    """Write the net at ``position`` (N, 3) m to ``path`` (.vtu) as :func:`jaxnet.io.vtk.write_vtu` does
    (displacement from the drawn shape, what holds each node, tensions, mesh opening angles, panel and cable
    ids, the names and mirror planes in field data), plus the point data ``velocity_m_s`` (N, 3) m/s when
    ``velocity`` is given and ``point_data`` (name -> (N, ...) array).

    Not the nodal forces by group nor the reactions of a static balance: at an instant of a run the net's
    inertia joins the balance, and evaluating every term at every record would make each record cost a
    solve's figures (a run's own reactions come as ``point_data``: :func:`record_point_data`). Nor the whole
    net of a model with symmetry planes: each record would be written ``1 + copies`` times over; the file
    states the planes (field data ``symmetry_planes``), which ParaView's Reflect filter takes.

    The file is written under a temporary name and renamed into place, so that ParaView, which may be
    reading the series while the run goes, never opens half a file.
    """
    path = pathlib.Path(path)
    tmp = path.with_name(path.stem + _PARTIAL + ".vtu")
    extra = dict(point_data or {})
    if velocity is not None:
        extra["velocity_m_s"] = np.asarray(velocity, dtype=float)
    vtk.write_vtu(tmp, scene, np.asarray(position), forces=False, point_data=extra, write_whole=False)
    if fsync:
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
    os.replace(tmp, path)
    if fsync:
        _sync_dir(path.parent)


def record_point_data(scene, record, run):
    """The point data of a record's .vtu besides its velocity: ``reaction_N`` (N, 3) in N, the record's figure
    ``reaction_N`` (one row per node of ``run["reaction_nodes"]``, as :func:`jaxnet.solve.dynamics.simulate`
    records them) put on its nodes, zero on the others; nothing when the record or the run lacks them."""
    reaction, rows = record.figures.get("reaction_N"), (run or {}).get("reaction_nodes")
    if reaction is None or rows is None:
        return {}
    reaction, rows = np.asarray(reaction, dtype=float), np.asarray(rows, dtype=np.int64)
    if reaction.shape != (len(rows), 3):
        return {}
    out = np.zeros((scene.n_nodes, 3))
    out[rows] = reaction
    return {"reaction_N": out}


def _vtu_name(k):
    return f"net_{k:05d}.vtu"


def _vtu_files(out_dir):
    """(path, record number) of the series' .vtu files in out_dir (not other .vtu files that may be there)."""
    found = ((path, re.fullmatch(r"net_(\d{5,})\.vtu", path.name)) for path in pathlib.Path(out_dir).glob("net_*.vtu"))
    return [(path, int(m.group(1))) for path, m in found if m]


def _pvd_text(entries):
    """ParaView collection of (time, file) entries. Times are written with repr: they read back exactly."""
    lines = ['<?xml version="1.0"?>', '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
             "  <Collection>"]
    lines += [f'    <DataSet timestep="{t!r}" group="" part="0" file={xml.sax.saxutils.quoteattr(name)}/>'
              for t, name in entries]
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------------
# Reading, and the resume point
# --------------------------------------------------------------------------------------------------


def read_series(out_dir) -> dict:
    """The complete records of the series in ``out_dir`` as numpy arrays: ``time`` (R,) s, ``step`` (R,)
    int64, ``position`` (R, N, 3) m, ``velocity`` (R, N, 3) m/s and each figure (R, ...).

    Works on a finished run, on one still being written (from any process) and on one that was killed: it
    reads the records the index counts and ignores anything beyond (a record being written, or half
    written when the run was killed; a record whose checkpoint got written but not its index entry is read
    once the run is resumed). A directory holding only ``series.npz`` (a finished run copied without its
    raw files) is read from that.
    """
    out_dir = pathlib.Path(out_dir)
    index = _read_index(out_dir)
    if index is None:
        if (out_dir / SERIES).exists():
            with np.load(out_dir / SERIES) as z:
                return {k: z[k] for k in z.files}
        raise FileNotFoundError(f"{out_dir}: no time series here ({INDEX} is missing)")
    count = index["records"]
    return {entry["name"]: _read_raw(out_dir, entry, count) for entry in index["arrays"]}


def _state(out_dir):
    """(index, checkpoint or None) of a series on disk, checked against each other (module docstring: the
    checkpoint's count c and the index's r satisfy r <= c <= r + 1)."""
    index = _read_index(out_dir)
    checkpoint = _read_checkpoint(out_dir)
    if index is None:
        if checkpoint is not None:
            raise SeriesError(f"{out_dir}: {CHECKPOINT} without {INDEX}: not a series this module wrote")
        return None, None
    r = index["records"]
    c = 0 if checkpoint is None else checkpoint[0]
    if not r <= c <= r + 1:
        raise SeriesError(f"{out_dir}: the index counts {r} records and the checkpoint is of record {c}; a run "
                          f"killed between the two writes leaves them at most one apart (checkpoint ahead), so "
                          f"these files do not belong to one run")
    if c == r and r > 0:
        # the checkpoint must be the index's last record: guards against files mixed from two runs
        entry = next(e for e in index["arrays"] if e["name"] == "time")
        last = _read_raw(out_dir, entry, r)[-1]
        if last != checkpoint[1].time:
            raise SeriesError(f"{out_dir}: the checkpoint's time {checkpoint[1].time!r} s is not the last record's "
                              f"{float(last)!r} s")
    return index, checkpoint


def resume_point(out_dir):
    """(Record, solver checkpoint dict) of the last complete record of the series in ``out_dir``: where a
    killed run resumes; None when there is no series there or it has no record yet.

    That record is the checkpoint's, which may be one record past what the index counts (the run was
    killed between the two writes; the checkpoint holds the whole record, and ``SeriesWriter(...,
    resume=True)`` counts it in). The solver's arrays come back as numpy arrays (0-d for scalars).
    """
    out_dir = pathlib.Path(out_dir)
    _, checkpoint = _state(out_dir)
    if checkpoint is None or checkpoint[0] == 0:
        return None
    return checkpoint[1], checkpoint[2]


# --------------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------------


class SeriesWriter:
    """Writes the records of a dynamic run to ``out_dir`` as they come (layout and order: module docstring).

    ``SeriesWriter(out_dir, scene, vtk=True, resume=False, fsync=False, run=None)``; a context manager (``close()``
    at the end, also when the run raised: what was recorded is kept).

    out_dir: the directory (created if missing). scene: the :class:`jaxnet.scene.Scene` being run (for
    the .vtu files and the counts in the index). vtk: write ``net_NNNNN.vtu`` and ``series.pvd``.
    resume: continue the series in ``out_dir`` after its last complete record (see :func:`resume_point`;
    ``resumed`` then holds (Record, solver checkpoint) to restart the solver from, or None when there was
    nothing to resume, and the writer starts a new series); without it, a series already in ``out_dir`` is
    replaced (its files are removed, and only those). fsync: force each write to the disk. run: what the
    index says of the run itself (a JSON-able dict, e.g. ``{"start_ramp_s": 6.0}``), under ``"run"``.
    """

    def __init__(self, out_dir, scene, vtk=True, resume=False, fsync=False, run=None):
        self.out_dir = pathlib.Path(out_dir)
        self.run = dict(run or {})
        self.scene = scene
        self.vtk = bool(vtk)
        self.fsync = bool(fsync)
        self.resumed = None
        self._files = {}
        self._closed = False
        self.out_dir.mkdir(parents=True, exist_ok=True)
        (self.out_dir / RAW).mkdir(exist_ok=True)
        for tmp in self.out_dir.glob(f"*{_PARTIAL}*"):
            tmp.unlink()
        n = scene.n_nodes
        self._base = {"time": ((), "<f8"), "step": ((), "<i8"), "position": ((n, 3), "<f8"),
                      "velocity": ((n, 3), "<f8")}
        index, checkpoint = _state(self.out_dir) if resume else (None, None)
        if index is None or checkpoint is None or checkpoint[0] == 0:
            self._start()
        else:
            self._resume(index, checkpoint)

    # -- opening

    def _start(self):
        """A new, empty series: remove an earlier one's files, write an index of no record."""
        for name in (INDEX, CHECKPOINT, SERIES, PVD):
            (self.out_dir / name).unlink(missing_ok=True)
        for path in (self.out_dir / RAW).glob("*.bin"):
            path.unlink()
        for path, _ in _vtu_files(self.out_dir):
            path.unlink()
        self.count = 0
        self._figures = None
        self._last = None
        self._pvd = []
        self._open_raw()
        self._write_index()
        if self.vtk:
            self._write_pvd()

    def _resume(self, index, checkpoint):
        """Continue a series: check it is this scene's, cut the raw files after the last complete record,
        roll the index forward when the checkpoint is one record ahead of it (module docstring)."""
        c, record, solver = checkpoint
        scene_info = index["scene"]
        if scene_info["n_nodes"] != self.scene.n_nodes or scene_info["n_elements"] != self.scene.n_elements:
            raise SeriesError(f"{self.out_dir}: the series is of a scene of {scene_info['n_nodes']} nodes and "
                              f"{scene_info['n_elements']} elements, not of this one ({self.scene.n_nodes} nodes, "
                              f"{self.scene.n_elements} elements)")
        r = index["records"]
        figures = {e["name"]: (tuple(e["shape"]), e["dtype"]) for e in index["arrays"] if e["name"] not in BASE}
        if r == 0:  # the layout of the figures is first known from the first record: here, the checkpoint's
            figures = {name: (np.shape(v), _figure_array(name, v).dtype.str) for name, v in record.figures.items()}
        self._figures = figures
        self.count = r
        for name, (shape, dtype) in {**self._base, **figures}.items():
            path = self.out_dir / _raw_file(name)
            size = r * _record_bytes(shape, dtype)
            if size and (not path.exists() or path.stat().st_size < size):
                raise SeriesError(f"{path}: shorter than the {r} records the index counts")
            if path.exists():
                os.truncate(path, size)
        for path, k in _vtu_files(self.out_dir):
            if k >= c:  # a record that was being written when the run was killed
                path.unlink()
        self._open_raw()
        times, steps = (_read_raw(self.out_dir, {"file": _raw_file(name), "shape": [], "dtype": dtype}, r)
                        for name, dtype in (("time", "<f8"), ("step", "<i8")))
        self._last = (float(times[-1]), int(steps[-1])) if r else None
        self._pvd = [(float(t), _vtu_name(k)) for k, t in enumerate(times) if (self.out_dir / _vtu_name(k)).exists()]
        if c == r + 1:
            arrays = self._check(record)
            self._append(arrays)
            if self.vtk and not (self.out_dir / _vtu_name(r)).exists():
                self._write_vtu(record, r)
            self._commit(record, r)
        elif self.vtk:
            self._write_pvd()
        self.resumed = (record, solver)

    def _open_raw(self):
        names = list(self._base) + list(self._figures or ())
        self._files = {name: open(self.out_dir / _raw_file(name), "ab") for name in names}

    # -- one record

    def _check(self, record):
        """The record as {array name: contiguous little-endian array}, or a SeriesError naming what differs
        from the series; nothing is written before this passes."""
        n = self.scene.n_nodes
        arrays = {"time": np.asarray(float(record.time), "<f8"), "step": np.asarray(int(record.step), "<i8")}
        for name in ("position", "velocity"):
            arr = np.asarray(record.position if name == "position" else record.velocity, dtype="<f8")
            if arr.shape != (n, 3):
                raise SeriesError(f"record at t = {record.time!r} s: {name} must have shape ({n}, 3), got {arr.shape}")
            arrays[name] = arr
        if self._last is not None and not (arrays["time"] > self._last[0] and arrays["step"] >= self._last[1]):
            raise SeriesError(f"record at t = {record.time!r} s (step {record.step}) does not come after the previous "
                              f"one (t = {self._last[0]!r} s, step {self._last[1]})")
        figures = {}
        for name, value in record.figures.items():
            if not isinstance(name, str) or not _NAME.match(name) or name in BASE:
                raise SeriesError(f"figure {name!r}: names must be identifiers (letters, digits, _) other than "
                                  f"{', '.join(BASE)}")
            figures[name] = _figure_array(name, value)
        if self._figures is not None:
            missing, extra = set(self._figures) - set(figures), set(figures) - set(self._figures)
            if missing or extra:
                what = (f"figure {sorted(missing)[0]!r} is missing" if missing else
                        f"figure {sorted(extra)[0]!r} was not in the first record")
                raise SeriesError(f"record at t = {record.time!r} s: {what}; the first record fixed the figures "
                                  f"{sorted(self._figures)}")
            for name, arr in figures.items():
                shape, dtype = self._figures[name]
                if arr.shape != tuple(shape):
                    raise SeriesError(f"record at t = {record.time!r} s: figure {name!r} has shape {arr.shape}, "
                                      f"the first record's was {tuple(shape)}")
                if np.dtype(dtype).kind == "i" and arr.dtype.kind != "i":
                    if not np.array_equal(arr, np.round(arr)):
                        raise SeriesError(f"record at t = {record.time!r} s: figure {name!r} is an integer "
                                          f"(first record) but got {arr!r}")
                figures[name] = arr.astype(dtype)
        arrays.update(figures)
        return arrays  # tobytes() writes C order whatever the memory layout

    def write(self, record: Record, checkpoint: dict | None = None):
        """Write one record, and the solver's ``checkpoint`` (name -> array: whatever it needs to resume
        exactly from this record; kept for the last record only). Raises SeriesError, having written
        nothing, when the record does not fit the series."""
        if self._closed:
            raise SeriesError(f"{self.out_dir}: the series writer is closed")
        arrays = self._check(record)
        if self._figures is None:
            self._figures = {name: (arr.shape, arr.dtype.str) for name, arr in arrays.items() if name not in BASE}
            for name in self._figures:
                self._files[name] = open(self.out_dir / _raw_file(name), "ab")
        k = self.count
        self._append(arrays)
        if self.vtk:
            self._write_vtu(record, k)
        solver = {f"solver.{name}": np.asarray(v) for name, v in (checkpoint or {}).items()}
        ckpt = {"records": np.asarray(k + 1), **{name: arrays[name] for name in BASE},
                **{f"figure.{name}": arrays[name] for name in self._figures}, **solver}
        _replace(self.out_dir / CHECKPOINT, lambda f: np.savez(f, **ckpt), self.fsync)
        self._commit(record, k)

    def _append(self, arrays):
        for name, f in self._files.items():
            f.write(arrays[name].tobytes())
            f.flush()
            if self.fsync:
                os.fsync(f.fileno())

    def _write_vtu(self, record, k):
        write_vtu_state(self.out_dir / _vtu_name(k), self.scene, record.position, record.velocity, self.fsync,
                        record_point_data(self.scene, record, self.run))

    def _commit(self, record, k):
        """Count record k in: the index, then the ParaView collection."""
        self.count = k + 1
        self._last = (float(record.time), int(record.step))
        self._write_index()
        if self.vtk:
            self._pvd.append((float(record.time), _vtu_name(k)))
            self._write_pvd()

    def _write_index(self):
        scene = self.scene
        layout = {**self._base, **(self._figures or {})}
        index = {
            "format": FORMAT, "version": VERSION, "records": self.count,
            "arrays": [{"name": name, "file": _raw_file(name), "shape": list(shape), "dtype": dtype}
                       for name, (shape, dtype) in layout.items()],
            "figures": list(self._figures or ()),
            "scene": {"n_nodes": scene.n_nodes, "n_elements": scene.n_elements, "n_dof": scene.n_dof,
                      "panel_names": list(scene.panel_names), "cable_names": list(scene.cable_names)},
            "checkpoint": CHECKPOINT, "vtk": self.vtk, "run": self.run,
        }
        text = json.dumps(index, indent=1).encode()
        _replace(self.out_dir / INDEX, lambda f: f.write(text), self.fsync)

    def _write_pvd(self):
        text = _pvd_text(self._pvd).encode()
        _replace(self.out_dir / PVD, lambda f: f.write(text), self.fsync)

    # -- closing

    def close(self):
        """Close the raw files and write ``series.npz`` (all complete records). Idempotent."""
        if self._closed:
            return
        self._closed = True
        for f in self._files.values():
            f.close()
        series = read_series(self.out_dir)
        _replace(self.out_dir / SERIES, lambda f: np.savez(f, **series), self.fsync)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
