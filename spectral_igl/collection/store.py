"""The Zarr store of a collection: one group per shape, written atomically.

Layout of ``out`` (a directory; Zarr format 3)::

    out/zarr.json            root group (attrs: layout version)
    out/<name>/              one group per shape: arrays + attrs (status "done" or "failed")
    out/.partial/            groups being written; never read as results

A shape's group is first written completely under ``.partial/`` (arrays, then attributes,
then a sync of the file system, one for a batch of groups), and only then renamed to
``out/<name>``: a rename within one file system is atomic, so a reader sees either the
whole previous record, nothing, or the whole new one.

The group's attributes are its completion record: with ``status`` they list every array's
shape, dtype and SHA-256 (``checksums``). :func:`check_record` compares the stored arrays
against it, so a group damaged later (a chunk deleted, a file truncated; Zarr would read a
missing chunk as zeros) is reported by :func:`load` and recomputed by a rerun, never read
as a result.
"""
from __future__ import annotations

import hashlib
import json
import math
import os
import shutil
import socket
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._extras import require

__all__ = ["ShapeResult", "Loaded", "load", "write_record", "stage_record", "publish",
           "read_record", "check_record", "clean_partial", "check_name", "lock_store", "StoreInUse", "PARTIAL", "LOCK", "LAYOUT",
           "BOUND_SUFFIX"]

PARTIAL = ".partial"
#: the lock file of a run in progress (JSON: host, pid, process start time, token)
LOCK = ".lock"
LAYOUT = 1
#: the array ``<key>_abs_error`` holds the per-entry bound of the stored result ``<key>``
BOUND_SUFFIX = "_abs_error"


def _zarr():
    zarr = require("zarr", "cluster", "spectral_igl.collection")
    if int(zarr.__version__.split(".")[0]) < 3:
        raise ImportError(f"spectral_igl.collection needs zarr >= 3, found {zarr.__version__}")
    return zarr


def check_name(name) -> str:
    """A shape name usable as a group name: a non-empty str without '/', not starting with '.'."""
    if not isinstance(name, str) or not name or "/" in name or "\\" in name or name.startswith(".") \
            or name.startswith("__"):
        raise ValueError(f"a shape name must be a non-empty str without '/' or '\\' that does not "
                         f"start with '.' or '__', got {name!r}")
    return name


def jsonable(x):
    """``x`` with numpy scalars/arrays as Python values and non-finite floats as None."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if math.isfinite(float(x)) else None
    if isinstance(x, (np.bool_,)):
        return bool(x)
    if x is None or isinstance(x, (str, int, bool)):
        return x
    return repr(x)


def open_root(out, mode="a"):
    """The root group of the store (created with ``mode="a"`` when absent)."""
    zarr = _zarr()
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise ValueError(f"out must be a directory for a Zarr store, got the file {str(out)!r}")
    if mode == "r":
        if not (path / "zarr.json").is_file():
            raise FileNotFoundError(f"no collection store at {str(out)!r} (no zarr.json)")
        return zarr.open_group(str(path), mode="r")
    root = zarr.open_group(str(path), mode="a", zarr_format=3)
    if "layout" not in root.attrs:
        root.attrs.update({"layout": LAYOUT, "content": "spectral_igl collection"})
    if not (path / PARTIAL / "zarr.json").is_file():
        part = zarr.open_group(str(path / PARTIAL), mode="a", zarr_format=3)
        part.attrs.update({"content": "groups being written; never a result"})
    return root


class StoreInUse(RuntimeError):
    """Another run holds the store's lock."""


def _proc_stat(pid: int):
    """``(state, start time)`` of process ``pid`` from ``/proc`` (Linux), ``(None, None)`` elsewhere."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()
        return fields[0], int(fields[19])
    except (OSError, ValueError, IndexError):
        return None, None


def _start_time(pid: int):
    """Start time of process ``pid`` (clock ticks since boot, Linux), None where unknown."""
    return _proc_stat(pid)[1]


def _alive(owner: dict) -> bool:
    """Whether the process that wrote the lock ``owner`` on this host still runs.

    A pid that exists but started at another time than the recorded one has been reused
    by another process after the owner died.
    """
    pid = owner.get("pid")
    if not isinstance(pid, int) or pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:      # exists, owned by another user
        pass
    state, now = _proc_stat(pid)
    if state in ("Z", "X"):      # killed, not yet reaped by its parent
        return False
    start = owner.get("start")
    return start is None or now is None or start == now


def _read_lock(path: Path):
    try:
        owner = json.loads(path.read_text())
        return owner if isinstance(owner, dict) else {}
    except FileNotFoundError:
        return None
    except (OSError, ValueError):
        return {}


class lock_store:
    """Hold the lock of the store ``out`` for one run (a context manager).

    The lock is the file ``out/.lock`` holding the host, pid and start time of the run that
    holds it, created atomically (written aside, then hard-linked into place, which fails
    when it exists). A second run on the same store is refused with :class:`StoreInUse`
    naming the holder. A lock left by a run that was killed (its process no longer runs
    on this host, or its pid now belongs to another process) is stale and taken over. A
    lock held from another host cannot be checked from here: the message says which file
    to remove once that run is known to be dead.
    """

    def __init__(self, out):
        self.path = Path(out) / LOCK
        self.token = uuid.uuid4().hex
        self.owner = {"host": socket.gethostname(), "pid": os.getpid(), "start": _start_time(os.getpid()),
                      "token": self.token, "since": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
        self.took_over = None

    def _link(self) -> bool:
        tmp = self.path.with_name(f"{LOCK}.{self.token}")
        tmp.write_text(json.dumps(self.owner))
        try:
            os.link(tmp, self.path)
            return True
        except FileExistsError:
            return False
        finally:
            tmp.unlink(missing_ok=True)

    def acquire(self):
        for _ in range(3):
            if self._link():
                return self
            owner = _read_lock(self.path)
            if owner is None:          # released meanwhile
                continue
            same_host = owner.get("host") == self.owner["host"]
            if owner and not (same_host and not _alive(owner)):
                where = "" if same_host else (" on another host: if that run is dead, remove "
                                              f"{str(self.path)!r}")
                raise StoreInUse(f"the store {str(self.path.parent)!r} is in use by another run (host "
                                 f"{owner.get('host')}, pid {owner.get('pid')}, since {owner.get('since')})"
                                 f"{where}; wait for it to finish, or write to another store")
            # stale (its process is gone) or unreadable: move it aside, check it is the one
            # judged stale, and try again
            aside = self.path.with_name(f"{LOCK}.stale.{self.token}")
            try:
                os.rename(self.path, aside)
            except FileNotFoundError:
                continue
            if (_read_lock(aside) or {}) != owner:    # another run took it over meanwhile
                try:
                    os.link(aside, self.path)
                except FileExistsError:
                    pass
                aside.unlink(missing_ok=True)
                continue
            aside.unlink(missing_ok=True)
            self.took_over = owner
        raise StoreInUse(f"could not take the lock {str(self.path)!r}: other runs keep taking it")

    def release(self):
        owner = _read_lock(self.path)
        if owner and owner.get("token") == self.token:
            self.path.unlink(missing_ok=True)

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()
        return False


def clean_partial(out) -> int:
    """Remove leftovers of interrupted writes; returns how many were removed."""
    part = Path(out) / PARTIAL
    n = 0
    if part.is_dir():
        for p in part.iterdir():
            if p.is_dir():
                shutil.rmtree(p, ignore_errors=True)
                n += 1
    return n


def _fsync_tree(path: Path):
    for dirpath, _, files in os.walk(path):
        for f in files:
            fd = os.open(os.path.join(dirpath, f), os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
        fd = os.open(dirpath, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _store_ready(out) -> None:
    """Create the store's root and ``.partial`` groups unless both exist (one stat each)."""
    root = Path(out)
    if not ((root / "zarr.json").is_file() and (root / PARTIAL / "zarr.json").is_file()):
        open_root(out)


#: dtype kinds written as raw little-endian chunks without going through zarr's machinery
_RAW_KINDS = "biufc"


def _fill_value(dtype: np.dtype):
    """The Zarr v3 JSON fill value 0 of a numeric dtype."""
    if dtype.kind == "b":
        return False
    if dtype.kind in "iu":
        return 0
    if dtype.kind == "c":
        return [0.0, 0.0]
    return 0.0


def _write_json(path: Path, doc: dict) -> None:
    path.write_text(json.dumps(doc, allow_nan=False))


def _write_array(group: Path, key: str, a: np.ndarray) -> None:
    """One array of a group: Zarr v3 metadata and one uncompressed chunk.

    Numeric arrays are written directly as the files zarr itself writes for an array of one
    chunk with the ``bytes`` codec (about 10x cheaper than zarr's API per small array);
    other dtypes and empty arrays go through zarr.
    """
    if a.dtype.kind not in _RAW_KINDS or a.size == 0:
        zarr = _zarr()
        g = zarr.open_group(str(group), mode="a", zarr_format=3)
        # every chunk is written, zeros included, so that a missing chunk means damage
        g.create_array(key, data=a, chunks=a.shape if a.size else "auto",
                       config={"write_empty_chunks": True})
        return
    a = np.ascontiguousarray(a, dtype=a.dtype.newbyteorder("<") if a.dtype.itemsize > 1 else a.dtype)
    codec = {"name": "bytes"}
    if a.dtype.itemsize > 1:
        codec["configuration"] = {"endian": "little"}
    where = group / key
    where.mkdir()
    _write_json(where / "zarr.json", {
        "zarr_format": 3, "node_type": "array", "shape": list(a.shape), "data_type": a.dtype.name,
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": list(a.shape)}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "fill_value": _fill_value(a.dtype), "codecs": [codec], "attributes": {},
        "storage_transformers": []})
    chunk = where.joinpath("c", *(["0"] * a.ndim)) if a.ndim else where / "c"
    chunk.parent.mkdir(parents=True, exist_ok=True)
    chunk.write_bytes(a.tobytes())


def _read_raw(where: Path):
    """The array at ``where`` if it is one uncompressed chunk as :func:`_write_array` writes it,
    else None (read it through zarr). Raises ValueError when the chunk's size is wrong."""
    doc = json.loads((where / "zarr.json").read_text())
    codecs = doc.get("codecs")
    if (not isinstance(codecs, list) or len(codecs) != 1 or codecs[0].get("name") != "bytes"
            or doc.get("chunk_grid", {}).get("configuration", {}).get("chunk_shape") != doc.get("shape")
            or doc.get("chunk_key_encoding", {}).get("configuration", {}).get("separator") != "/"):
        return None
    shape = tuple(doc["shape"])
    try:
        dtype = np.dtype(doc["data_type"]).newbyteorder("<")
    except TypeError:
        return None
    if dtype.kind not in _RAW_KINDS or not shape or 0 in shape:
        return None
    data = where.joinpath("c", *(["0"] * len(shape))).read_bytes()
    if len(data) != dtype.itemsize * int(np.prod(shape)):
        raise ValueError(f"chunk of {len(data)} bytes, {dtype.itemsize * int(np.prod(shape))} expected")
    return np.frombuffer(data, dtype=dtype).reshape(shape).astype(dtype.newbyteorder("="))


def _sync_fs(path: Path, trees) -> None:
    """Make the files of ``trees`` durable: one ``syncfs`` of ``path``'s file system (Linux),
    else an fsync of every file and directory of each tree."""
    try:
        import ctypes

        syncfs = ctypes.CDLL(None, use_errno=True).syncfs
    except (AttributeError, OSError):
        syncfs = None
    if syncfs is not None:
        fd = os.open(path, os.O_RDONLY)
        try:
            if syncfs(fd) == 0:
                return
        finally:
            os.close(fd)
    for tree in trees:
        _fsync_tree(tree)


def stage_record(out, name, attrs: dict, arrays: dict | None = None) -> Path:
    """Write one shape's group under ``out/.partial`` (not yet durable nor visible).

    Parameters are those of :func:`write_record`; returns the staged group's path, to be
    handed to :func:`publish`.
    """
    name = check_name(name)
    _store_ready(out)
    tmp = Path(out) / PARTIAL / f"{name}.{uuid.uuid4().hex[:12]}"
    tmp.mkdir()
    sums = {}
    for key, value in (arrays or {}).items():
        a = np.ascontiguousarray(value)
        if a.dtype.byteorder not in "=|":     # read back in native order: checksum that
            a = a.astype(a.dtype.newbyteorder("="))
        _write_array(tmp, str(key), a)
        sums[str(key)] = _checksum(a)
    meta = dict(attrs)
    meta["arrays"] = sorted(sums)
    meta["checksums"] = sums
    # the group's metadata last: a group without it is never read as a result
    _write_json(tmp / "zarr.json", {"zarr_format": 3, "node_type": "group", "attributes": jsonable(meta)})
    return tmp


def publish(out, staged) -> None:
    """Make staged groups durable (one file-system sync for all), then rename each into place.

    Parameters
    ----------
    out : path of the store
    staged : list of (name, path)
        Names and the paths :func:`stage_record` returned.
    """
    root = Path(out)
    if not staged:
        return
    _sync_fs(root / PARTIAL, [tmp for _, tmp in staged])
    old = []
    for name, tmp in staged:
        dest = root / name
        if dest.exists():
            aside = tmp.with_name(tmp.name + ".old")
            os.rename(dest, aside)
            old.append(aside)
        os.rename(tmp, dest)
    fd = os.open(root, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    for aside in old:
        shutil.rmtree(aside, ignore_errors=True)


def write_record(out, name, attrs: dict, arrays: dict | None = None) -> None:
    """Write one shape's group atomically (temporary group, sync, then rename).

    Parameters
    ----------
    out : path of the store (created if absent)
    name : str
        Group name (see :func:`check_name`).
    attrs : dict
        Metadata, stored as JSON (numpy values converted, non-finite floats as null).
        Must hold ``status``.
    arrays : dict of str -> ndarray
    """
    publish(out, [(check_name(name), stage_record(out, name, attrs, arrays))])


def _checksum(a: np.ndarray) -> dict:
    """Shape, dtype and SHA-256 of an array's bytes (C order): its entry in the completion record."""
    a = np.ascontiguousarray(a)
    return {"shape": list(a.shape), "dtype": a.dtype.str, "sha256": hashlib.sha256(a.tobytes()).hexdigest()}


def _attributes(path: Path):
    """``(attrs, problem)`` read from ``path/zarr.json``: problem is None, or says what is wrong."""
    meta = path / "zarr.json"
    if not meta.is_file():
        return None, "no zarr.json (the group's metadata is missing)"
    try:
        doc = json.loads(meta.read_text())
    except (OSError, ValueError) as err:
        return None, f"zarr.json is unreadable or truncated ({type(err).__name__}: {err})"
    attrs = doc.get("attributes") if isinstance(doc, dict) else None
    if not isinstance(attrs, dict) or attrs.get("status") not in ("done", "failed"):
        return None, "zarr.json holds no completion record (status 'done' or 'failed')"
    return attrs, None


def read_record(out, name) -> dict | None:
    """The attributes of ``out/<name>`` if its completion record is readable, else None.

    Only the metadata is read; :func:`check_record` also verifies the arrays.
    """
    attrs, problem = _attributes(Path(out) / name)
    if problem is not None:
        return None
    if any(not (Path(out) / name / a / "zarr.json").is_file() for a in attrs.get("arrays", [])):
        return None
    return attrs


def check_record(out, name, data: bool = True):
    """Verify ``out/<name>`` against its completion record.

    Parameters
    ----------
    out : path of the store
    name : str
        Group name.
    data : bool
        Also read every array and compare its shape, dtype and SHA-256 with the record
        (``False``: only that each array's metadata and chunk files are present).

    Returns
    -------
    attrs : dict or None
        The record's attributes (None when they cannot be read).
    arrays : dict of str -> ndarray
        The verified arrays (empty with ``data=False``).
    problem : str or None
        What is damaged; None for an intact group.
    """
    zarr = _zarr()
    path = Path(out) / name
    attrs, problem = _attributes(path)
    if problem is not None:
        return None, {}, problem
    sums = attrs.get("checksums", {})
    arrays = {}
    for key in attrs.get("arrays", []):
        where = path / key
        if not (where / "zarr.json").is_file():
            return attrs, {}, f"array {key!r} is missing (no {key}/zarr.json)"
        want = sums.get(key)     # None in records written before checksums were kept
        if want is not None and int(np.prod(want["shape"])) and not any(p.is_file() for p in where.rglob("*") if p.name != "zarr.json"):
            return attrs, {}, f"array {key!r} has no data chunks (deleted)"
        if not data:
            continue
        try:
            a = _read_raw(where)
            if a is None:
                a = np.asarray(zarr.open_array(str(where), mode="r")[...])
        except Exception as err:  # noqa: BLE001 - any failure to decode is damage
            return attrs, {}, f"array {key!r} cannot be read ({type(err).__name__}: {err})"
        if want is not None and _checksum(a) != want:
            got = _checksum(a)
            what = ("shape/dtype " + f"{tuple(got['shape'])} {got['dtype']}, recorded "
                    f"{tuple(want['shape'])} {want['dtype']}" if got["shape"] != want["shape"]
                    or got["dtype"] != want["dtype"] else "checksum differs from the recorded one")
            return attrs, {}, f"array {key!r} is damaged: {what}"
        arrays[key] = a
    return attrs, arrays, None


@dataclass
class ShapeResult:
    """One shape's stored result: its arrays and its metadata.

    The accuracy of the result (:mod:`spectral_igl.accuracy`) is kept with it:
    ``meta["bounds"]`` holds ``abs_error`` (the largest per-entry bound, ``None`` without
    one), ``bound_kind``, ``method``, ``of`` (the bounded array) and, where the job gives
    one, a ``note``; the per-entry bound is the array ``<of>_abs_error``. Read them with
    :meth:`abs_error` and :attr:`bound_kind`.

    Parameters
    ----------
    name : str
        The shape's name in the store.
    arrays : dict of str -> ndarray
        Its stored arrays (empty when loaded with ``arrays=False``).
    meta : dict
        Its metadata: ``input_hash``, ``mesh_hash``, ``version``, ``job``, ``params``,
        ``timings``, ``bounds``...

    Examples
    --------
    >>> import numpy as np
    >>> from spectral_igl.collection import ShapeResult
    >>> r = ShapeResult("cow", {"hks": np.ones((3, 2))},
    ...                 {"bounds": {"abs_error": 1e-9, "bound_kind": "proof", "of": "hks"}})
    >>> r.bound_kind, float(r.abs_error("hks").max())
    ('proof', 1e-09)
    """

    name: str
    arrays: dict = field(default_factory=dict)
    meta: dict = field(default_factory=dict)

    def __getitem__(self, key):
        return self.arrays[key]

    @property
    def bound_kind(self):
        """``"proof"``, ``"estimate"`` or ``None`` (no bound) for the stored result."""
        return self.meta.get("bounds", {}).get("bound_kind")

    def abs_error(self, key: str):
        """Bound of every entry of ``arrays[key]``: the stored per-entry bound, else the stored
        largest bound at every entry (a float when the arrays were not loaded); ``nan`` where
        the result has none (``key`` is not the bounded result, or the job gives no bound)."""
        per = self.arrays.get(key + BOUND_SUFFIX)
        if per is not None:
            return per
        bounds = self.meta.get("bounds", {})
        top = bounds.get("abs_error") if bounds.get("of") == key else None
        top = float("nan") if top is None else float(top)
        return np.full(self.arrays[key].shape, top) if key in self.arrays else top


class Loaded(tuple):
    """``(results, failures)``: results by shape name, and one dict per failed shape.

    What :func:`load` returns; it unpacks as a pair and names its parts.

    Parameters
    ----------
    results : dict of str -> ShapeResult
        Every completed shape.
    failures : list of dict
        One dict per failed or damaged shape (``name``, ``source``, ``error``...).

    Attributes
    ----------
    results, failures
        The two parts by name.

    Examples
    --------
    >>> from spectral_igl.collection import Loaded
    >>> got = Loaded({}, [{"name": "bad", "source": "bad.obj", "error": "no faces"}])
    >>> results, failures = got
    >>> print(got.failure_table())
    name  source   error
    bad   bad.obj  no faces
    """

    def __new__(cls, results, failures):
        return super().__new__(cls, (results, failures))

    @property
    def results(self) -> dict:
        return self[0]

    @property
    def failures(self) -> list:
        return self[1]

    def failure_table(self) -> str:
        """The failures as aligned text: name, source, error."""
        rows = [(f["name"], str(f.get("source") or ""), f.get("error", "")) for f in self.failures]
        if not rows:
            return "no failures"
        w0 = max(len("name"), *(len(r[0]) for r in rows))
        w1 = max(len("source"), *(len(r[1]) for r in rows))
        lines = [f"{'name':<{w0}}  {'source':<{w1}}  error"]
        lines += [f"{a:<{w0}}  {b:<{w1}}  {c}" for a, b, c in rows]
        return "\n".join(lines)


def load(out, arrays: bool = True) -> Loaded:
    """Read a collection store back.

    Parameters
    ----------
    out : str or os.PathLike
        The store written by :func:`spectral_igl.collection.run`.
    arrays : bool
        Read the arrays into memory (``False``: metadata only).

    Returns
    -------
    results : dict of str -> ShapeResult
        Every completed shape: ``results[name].arrays["hks"]`` is an (n, T) float array,
        ``results[name].meta`` its metadata (``input_hash``, ``mesh_hash``, ``version``,
        ``job``, ``params``, ``timings``, ``bounds``...).
    failures : list of dict
        One dict per failed shape: ``name``, ``source``, ``error``, ``input_hash``...
        A group damaged after it was written (a deleted chunk, a truncated ``zarr.json``,
        an array whose checksum differs from its completion record) is listed here with
        ``damaged: True`` and the problem in ``error``, never among the results; a rerun
        of :func:`~spectral_igl.collection.run` recomputes it. Groups left half-written by
        an interruption (under ``.partial``) are never listed.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.collection import Job, load, run
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(2)
    >>> _ = run({"ball": (V, F)}, Job.eigenvalues(4), "ball.zarr", workers=1, progress=False)
    >>> results, failures = load("ball.zarr")
    >>> ev = results["ball"].arrays["eigenvalues"]
    >>> bool(np.all(np.abs(ev - sig.dense_eigs(sig.laplacian(V, F))[0][:4])
    ...             <= results["ball"].abs_error("eigenvalues") + 1e-12))
    True
    """
    root = Path(out)
    open_root(out, mode="r")
    if not isinstance(arrays, (bool, np.bool_)):
        raise TypeError(f"arrays must be True or False, got {type(arrays).__name__} {arrays!r}")
    results, failures = {}, []
    for p in sorted(root.iterdir()):
        if not p.is_dir() or p.name.startswith("."):
            continue
        attrs, data, problem = check_record(out, p.name, data=bool(arrays))
        if problem is not None:
            failures.append(dict(attrs or {}, name=p.name, status="damaged", damaged=True,
                                 error=f"damaged record: {problem}"))
            continue
        if attrs["status"] == "failed":
            failures.append(dict(attrs, name=p.name))
            continue
        results[p.name] = ShapeResult(p.name, data, attrs)
    return Loaded(results, failures)
