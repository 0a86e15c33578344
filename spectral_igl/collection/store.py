"""The Zarr store of a collection: one group per shape, written atomically.

Layout of ``out`` (a directory; Zarr format 3)::

    out/zarr.json            root group (attrs: layout version)
    out/<name>/              one group per shape: arrays + attrs (status "done" or "failed")
    out/.partial/            groups being written; never read as results

A shape's group is first written completely under ``.partial/`` (arrays, then attributes,
then fsync), and only then renamed to ``out/<name>``: a rename within one file system is
atomic, so a reader sees either the whole previous record, nothing, or the whole new one.
"""
from __future__ import annotations

import json
import math
import os
import shutil
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._extras import require

__all__ = ["ShapeResult", "Loaded", "load", "write_record", "read_record", "clean_partial",
           "check_name", "PARTIAL", "LAYOUT", "BOUND_SUFFIX"]

PARTIAL = ".partial"
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


def write_record(out, name, attrs: dict, arrays: dict | None = None) -> None:
    """Write one shape's group atomically (temporary group, then rename).

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
    zarr = _zarr()
    name = check_name(name)
    open_root(out)
    arrays = arrays or {}
    root = Path(out)
    tag = uuid.uuid4().hex[:12]
    tmp = root / PARTIAL / f"{name}.{tag}"
    g = zarr.open_group(str(tmp), mode="w", zarr_format=3)
    for key, value in arrays.items():
        a = np.ascontiguousarray(value)
        g.create_array(str(key), data=a, chunks=a.shape if a.size else "auto")
    meta = dict(attrs)
    meta["arrays"] = sorted(str(k) for k in arrays)
    g.attrs.update(jsonable(meta))
    _fsync_tree(tmp)
    dest = root / name
    old = None
    if dest.exists():
        old = root / PARTIAL / f"{name}.{tag}.old"
        os.rename(dest, old)
    os.rename(tmp, dest)
    fd = os.open(root, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def read_record(out, name) -> dict | None:
    """The attributes of ``out/<name>`` if it is a complete record, else None."""
    path = Path(out) / name
    meta = path / "zarr.json"
    if not meta.is_file():
        return None
    try:
        attrs = json.loads(meta.read_text()).get("attributes", {})
    except (OSError, ValueError):
        return None
    if attrs.get("status") not in ("done", "failed"):
        return None
    if any(not (path / a / "zarr.json").is_file() for a in attrs.get("arrays", [])):
        return None
    return attrs


@dataclass
class ShapeResult:
    """One shape's stored result: its arrays and its metadata.

    The accuracy of the result (:mod:`spectral_igl.accuracy`) is kept with it:
    ``meta["bounds"]`` holds ``abs_error`` (the largest per-entry bound, ``None`` without
    one), ``bound_kind``, ``method``, ``of`` (the bounded array) and, where the job gives
    one, a ``note``; the per-entry bound is the array ``<of>_abs_error``. Read them with
    :meth:`abs_error` and :attr:`bound_kind`.
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
    """``(results, failures)``: results by shape name, and one dict per failed shape."""

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
        Groups left half-written by an interruption are never listed.
    """
    zarr = _zarr()
    root = Path(out)
    open_root(out, mode="r")
    results, failures = {}, []
    for p in sorted(root.iterdir()):
        if not p.is_dir() or p.name.startswith("."):
            continue
        attrs = read_record(out, p.name)
        if attrs is None:
            continue
        if attrs["status"] == "failed":
            failures.append(dict(attrs, name=p.name))
            continue
        data = {}
        if arrays:
            g = zarr.open_group(str(p), mode="r")
            data = {a: np.asarray(g[a][...]) for a in attrs.get("arrays", [])}
        results[p.name] = ShapeResult(p.name, data, attrs)
    return Loaded(results, failures)
