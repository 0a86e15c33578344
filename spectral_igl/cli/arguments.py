"""The argument blocks the jobs share, written once: value types, the input (mesh or
generated shape, Laplacian, outputs), the engine (source, filter, time, method, accuracy),
the time unit, the pictures and the progress bar."""
from __future__ import annotations

import argparse

import numpy as np

from ..approx import METHODS
from ..diagonal import METHODS as DIAGONAL_METHODS
from ..distances import MAX_ORDER
from ..filters import FILTERS
from ..laplacian.units import TIME_UNITS
from .outputs import OUTPUTS

__all__ = ["FILTER_NAMES", "SHAPES", "positive", "nonnegative", "positive_int", "vertex_index",
           "order", "tolerance", "view", "input_args", "operator_args", "progress_arg",
           "picture_args", "quiet_arg", "time_args", "time_unit_arg", "source_arg", "method_arg",
           "tol_arg", "diagonal_arg", "engine_args"]

FILTER_NAMES = tuple(FILTERS)
#: the generated shapes of ``--shape``
SHAPES = ("sphere", "box", "torus", "cylinder")


# ---- value types ------------------------------------------------------------------------
def _number_type(convert, accept, expected, refused=None):
    """An argparse type: ``convert`` the text, then require ``accept`` of the value; the
    message says what was ``expected`` (``refused``: another wording for a value that
    converts but is not accepted)."""
    def parse(text):
        try:
            x = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
        if not accept(x):
            raise argparse.ArgumentTypeError(f"expected {refused or expected}, got {text!r}")
        return x

    return parse


positive = _number_type(float, lambda x: np.isfinite(x) and x > 0, "a positive number")
nonnegative = _number_type(float, lambda x: np.isfinite(x) and x >= 0, "a number >= 0",
                           "a finite number >= 0")
vertex_index = _number_type(int, lambda x: x >= 0, "a vertex index (integer >= 0)")
positive_int = _number_type(int, lambda x: x > 0, "a positive integer")


def order(text):
    """An order of the polyharmonic filter, 1 to ``MAX_ORDER``."""
    x = positive_int(text)
    if x > MAX_ORDER:
        raise argparse.ArgumentTypeError(f"expected an order from 1 to {MAX_ORDER}, got {text!r}")
    return x


def tolerance(text):
    """A relative tolerance in (0, 1)."""
    x = positive(text)
    if x >= 1:
        raise argparse.ArgumentTypeError(f"expected a relative tolerance in (0, 1), got {text!r}")
    return x


def view(text):
    """A camera of :func:`spectral_igl.viz.parse_view`, kept as text."""
    from ..viz import parse_view

    try:
        parse_view(text)
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None
    return text


# ---- argument blocks --------------------------------------------------------------------
def input_args(p, outputs=OUTPUTS):
    """MESH or ``--shape``, the Laplacian, outputs, ``--quiet``, progress and pictures."""
    p.add_argument("mesh", nargs="?", metavar="MESH",
                   help="mesh file: .obj .off .ply .stl .wrl (triangles) or .mesh (tetrahedra)")
    p.add_argument("--shape", choices=SHAPES,
                   help="use a generated shape instead of a file: sphere (unit icosphere), "
                        "torus (R = 1, r = 0.4), cylinder (open, radius 1, height 2), "
                        "box (tetrahedral box 1 x 0.75 x 0.5)")
    p.add_argument("--level", type=int, default=3,
                   help="resolution of the generated shape, 1 to 7 (sphere: icosphere "
                        "subdivisions, 642 vertices at 3; default 3)")
    operator_args(p)
    p.add_argument("-o", "--out", action="append", default=[], metavar="FILE",
                   help=f"write the result; type by extension ({', '.join(outputs)}); repeatable")
    quiet_arg(p, "print nothing on success (and draw no progress bar)")
    progress_arg(p)
    picture_args(p)


def operator_args(p, described=True):
    """``--weights`` and ``--mass`` of the Laplacian (``described``: with their help)."""
    p.add_argument("--weights", default="auto", choices=("auto", "cotan", "intrinsic_delaunay", "uniform"),
                   help="Laplacian weights (default auto: intrinsic Delaunay for triangles, cotan "
                        "for tets)" if described else None)
    p.add_argument("--mass", default="lumped", choices=("lumped", "full", "barycentric"),
                   help="mass matrix (default lumped: with auto weights the heat stays "
                        "non-negative)" if described else None)


def progress_arg(p):
    """``--progress`` / ``--no-progress``."""
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=True,
                   help="progress bars on stderr, one step per factorization, pole, time or "
                        "figure (default: on)")


def picture_args(p):
    """``--view`` and ``--cmap`` of pictures."""
    p.add_argument("--view", default="auto", type=view, metavar="VIEW",
                   help="camera of pictures: auto (face the source from outside the shape), "
                        "iso, +x, -x, +y, -y, +z, -z, or a direction dx,dy,dz (default auto)")
    p.add_argument("--cmap", default=None, metavar="NAME",
                   help="colour map of pictures (a matplotlib name); default by meaning: "
                        "sequential for distances and non-negative values, diverging centred "
                        "at 0 for signed ones")


def quiet_arg(p, help=None):
    """``-q`` / ``--quiet``."""
    p.add_argument("-q", "--quiet", action="store_true", help=help)


def time_args(p, help, what="-t"):
    """``-t`` / ``--time`` (optional) and its ``--time-unit``."""
    p.add_argument("-t", "--time", type=positive, default=None, help=help)
    time_unit_arg(p, what)


def time_unit_arg(p, what="-t"):
    """``--time-unit`` of the times named ``what``."""
    p.add_argument("--time-unit", default=None, choices=TIME_UNITS,
                   help=f"unit of {what}: absolute (as given; the default), shape (x the area of a "
                        "surface, x volume^(2/3) of a solid: the same meaning on a mesh of any size "
                        "or unit), area, volume, h2 (x the squared mean edge length)")


def source_arg(p, help):
    """``-s`` / ``--source``: one vertex, default 0."""
    p.add_argument("-s", "--source", type=vertex_index, default=0, help=help)


def method_arg(p):
    """``--method`` of the approximation engine."""
    p.add_argument("--method", default="auto", choices=METHODS, metavar="METHOD",
                   help=f"approximation method: {', '.join(METHODS)} (default auto)")


def tol_arg(p, help=None, kind=tolerance):
    """``--tol``, the target accuracy (default 1e-8)."""
    p.add_argument("--tol", type=kind, default=1e-8, help=help)


def diagonal_arg(p, help):
    """``--diagonal``: how a kernel diagonal is obtained."""
    p.add_argument("--diagonal", default="auto", choices=DIAGONAL_METHODS, help=help)


def engine_args(p, filter_default, t_help="time/scale t of the filter (default: 1e-2 x area of "
                                             "a surface, x volume^(2/3) of a solid)"):
    """Source, filter, time, order, method, accuracy and diagonal of a kernel or distance."""
    source_arg(p, "source vertex index (default 0)")
    p.add_argument("-f", "--filter", default=filter_default, choices=FILTER_NAMES, metavar="FILTER",
                   help=f"spectral filter: {', '.join(FILTER_NAMES)} (default {filter_default})")
    time_args(p, t_help)
    p.add_argument("--order", type=order, default=3,
                   help=f"order k of the polyharmonic filter, 1 to {MAX_ORDER} (default 3)")
    method_arg(p)
    tol_arg(p, "target accuracy, in (0, 1) (default 1e-8)")
    diagonal_arg(p, "distances: how the kernel diagonal is obtained (selinv: selected "
                    "inversion, certified; exact: one application per vertex; probing: "
                    "colouring estimator; default auto: selinv where it applies)")
