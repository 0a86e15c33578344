"""Where to look from: a camera that faces the source from outside the shape.

Only numpy (and scipy) at import time; the occlusion test uses VTK's cell locator, imported
when a camera is placed.
"""
from __future__ import annotations

import numpy as np

__all__ = ["VIEWS", "parse_view", "auto_view", "up_direction", "principal_axes", "frame_directions",
           "visible_fraction", "view_sees", "place_camera"]

#: named views: the direction from the centre of the shape towards the camera
VIEWS = {
    "+x": (1.0, 0.0, 0.0), "-x": (-1.0, 0.0, 0.0),
    "+y": (0.0, 1.0, 0.0), "-y": (0.0, -1.0, 0.0),
    "+z": (0.0, 0.0, 1.0), "-z": (0.0, 0.0, -1.0),
    "iso": (1.0, 1.0, 1.0),
}
#: the vertical angle of VTK's default perspective camera (degrees)
VIEW_ANGLE = 30.0


def parse_view(view):
    r"""Normalise a view request.

    Parameters
    ----------
    view : None, str, (3,) float or pyvista camera position
        ``None`` or ``"auto"``: choose (see :func:`spectral_igl.viz.auto_view`); a name in ``VIEWS``
        (``"iso"``, ``"+x"``, ``"-z"``, ...); a direction ``(dx, dy, dz)`` (from the shape
        towards the camera; also as the string ``"1,0.5,0"``); or a full pyvista camera
        position ``[position, focal_point, view_up]`` or a pyvista name (``"xy"``, ...).

    Returns
    -------
    ("auto", None) or ("direction", (3,) float) or ("pyvista", object)

    Examples
    --------
    >>> from spectral_igl import viz
    >>> viz.parse_view(None), viz.parse_view("+x")[1].tolist(), viz.parse_view("0,0,2")[1].tolist()
    (('auto', None), [1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    """
    if view is None or (isinstance(view, str) and view.strip().lower() == "auto"):
        return "auto", None
    if isinstance(view, str):
        key = view.strip().lower()
        if key in VIEWS:
            d = np.asarray(VIEWS[key], dtype=float)
            return "direction", d / np.linalg.norm(d)
        if key in ("x", "y", "z"):
            return "direction", np.asarray(VIEWS["+" + key], dtype=float)
        if key in ("xy", "xz", "yz", "yx", "zx", "zy"):
            return "pyvista", key
        try:
            d = np.array([float(s) for s in key.replace(" ", "").split(",")])
        except ValueError:
            d = None
        if d is None or d.shape != (3,):
            raise ValueError(f"camera/view must be 'auto', one of {', '.join(VIEWS)}, or a direction "
                             f"'dx,dy,dz'; got {view!r}")
    else:
        try:
            d = np.asarray(view, dtype=float)
        except (TypeError, ValueError):
            return "pyvista", view
        if d.shape == (3, 3):
            return "pyvista", [tuple(r) for r in d]
        if d.shape != (3,):
            raise ValueError(f"camera/view direction must have 3 components, got shape {d.shape}")
    if not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0:
        raise ValueError(f"camera/view direction must be finite and non-zero, got {view!r}")
    return "direction", d / np.linalg.norm(d)


def _unit(x):
    x = np.asarray(x, dtype=float)
    n = np.linalg.norm(x)
    return x / n if n > 0 else x


def principal_axes(points, faces=None):
    """Centre and principal axes of a shape, weighted by area when there are triangles.

    A scan samples its surface unevenly; weighting each triangle's centroid by its area
    (plus the spread inside the triangle) makes the axes those of the surface, not of the
    sampling. Without triangles the points weigh the same.

    Parameters
    ----------
    points : (n, 3) float
    faces : (m, 3) int, optional

    Returns
    -------
    centre : (3,) float
    axes : (3, 3) float
        Unit rows, largest spread first.
    spread : (3,) float
        Standard deviations along the axes.

    Examples
    --------
    >>> P = np.array([[0, 0, 0], [4, 4, 0], [2, 2, 1], [2, 2, -1], [1, 1, 0], [3, 3, 0]], float)
    >>> c, axes, s = principal_axes(P)
    >>> np.round(np.abs(axes[0]), 3)
    array([0.707, 0.707, 0.   ])
    """
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    if faces is not None and len(faces):
        F = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        A, B, C = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
        w = 0.5 * np.linalg.norm(np.cross(B - A, C - A), axis=1)
        if w.sum() > 0:
            cen = (A + B + C) / 3.0
            centre = (w[:, None] * cen).sum(0) / w.sum()
            # second moment of each triangle about the centre: exact for a uniform density
            M = sum(np.einsum("k,ki,kj->ij", w, X - centre, X - centre) for X in (A, B, C)) / 12.0
            M += np.einsum("k,ki,kj->ij", w, cen - centre, cen - centre) * 0.75
            M /= w.sum()
            return _axes_of(centre, M)
    if len(P) == 0:
        return np.zeros(3), np.eye(3), np.zeros(3)
    centre = P.mean(0)
    return _axes_of(centre, (P - centre).T @ (P - centre) / len(P))


def _axes_of(centre, M):
    vals, vecs = np.linalg.eigh(M)
    order = np.argsort(vals)[::-1]
    return centre, vecs.T[order], np.sqrt(np.maximum(vals[order], 0.0))


def _sign_up(a):
    """``a`` or ``-a``: the one along the file's ``y`` (then ``z``, then ``x``) where that is clear."""
    for k in (1, 2, 0):
        if abs(a[k]) > 0.2:
            return a if a[k] > 0 else -a
    return a


def up_direction(points, direction, faces=None):
    """An up vector from the shape's principal axes, orthogonal to the view ``direction``.

    The candidates are the principal axes of the shape (area-weighted with ``faces``,
    :func:`principal_axes`), never the file's axes: a scan tilted in its file is drawn
    along its own axes. An axis within 30 degrees of the file's ``y`` (then ``z``) axis is
    kept as up (an upright file stays upright; a scan tilted by 45 degrees has none); otherwise the axis of largest spread wins.
    Axes closer than ~37 degrees to the view do not count (they shrink once projected);
    without any other, the one most orthogonal to the view is used. The sign follows the
    file's ``y`` (then ``z``, ``x``) axis where the axis has a clear component along it.

    Parameters
    ----------
    points : (n, 3) float
    direction : (3,) float
    faces : (m, 3) int, optional

    Returns
    -------
    (3,) float, a unit vector orthogonal to ``direction``.
    """
    P = np.asarray(points, dtype=float)
    d = _unit(direction)
    axes = principal_axes(P, faces)[1] if len(P) >= 3 else np.eye(3)
    upright = [a for a in axes if abs(a @ d) < 0.8]
    if upright:
        a = _vertical(upright)
    else:
        a = axes[int(np.argmin(np.abs(axes @ d)))]
    a = _sign_up(a)
    up = a - (a @ d) * d
    if np.linalg.norm(up) < 1e-6:  # view along the axis: any orthogonal vector
        up = np.cross(d, [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 1.0, 0.0])
    return _unit(up)


def _vertical(axes):
    """The principal axis drawn upright: one within 30 degrees of the file's ``y`` (then
    ``z``) axis if there is one, else the first (the largest spread)."""
    for k in (1, 2):  # an axis along the file's vertical keeps an upright file upright
        along = [b for b in axes if abs(b[k]) > np.cos(np.radians(30.0))]
        if along:
            return along[0]
    return axes[0]


def frame_directions(axes):
    """The six principal directions and the eight diagonals of the frame ``axes`` (rows)."""
    axes = np.asarray(axes, dtype=float)
    out = [s * a for a in axes for s in (1.0, -1.0)]
    out += [_unit(sx * axes[0] + sy * axes[1] + sz * axes[2]) for sx in (1, -1) for sy in (1, -1)
            for sz in (1, -1)]
    return out


class _Occluder:
    """Segment/surface intersection test on a triangle surface (VTK static cell locator)."""

    def __init__(self, surface):
        from vtkmodules.vtkCommonDataModel import vtkStaticCellLocator

        self.surface = surface
        self.locator = vtkStaticCellLocator()
        self.locator.SetDataSet(surface)
        self.locator.BuildLocator()

    def blocked(self, a, b) -> bool:
        from vtkmodules.vtkCommonCore import vtkPoints
        from vtkmodules.vtkCommonCore import vtkIdList

        pts, ids = vtkPoints(), vtkIdList()
        self.locator.IntersectWithLine(tuple(map(float, a)), tuple(map(float, b)), 0.0, pts, ids)
        return ids.GetNumberOfIds() > 0


def camera_distance(radius, view_angle=VIEW_ANGLE):
    """Distance from the focal point at which VTK's ``reset_camera`` fits a sphere of ``radius``."""
    return float(radius) / np.sin(np.radians(view_angle) / 2.0)


def visible_fraction(occluder, targets, focal, radius, direction, eps):
    """Fraction of ``targets`` (k, 3) seen unobstructed from the camera placed along ``direction``."""
    eye = np.asarray(focal) + camera_distance(radius) * _unit(direction)
    seen = 0
    for q in np.atleast_2d(targets):
        to_eye = eye - q
        dist = np.linalg.norm(to_eye)
        if dist <= eps:
            seen += 1
            continue
        start = q + eps * to_eye / dist  # leave the surface the point lies on
        seen += not occluder.blocked(start, eye)
    return seen / max(len(np.atleast_2d(targets)), 1)


def view_sees(surface, point, eye) -> bool:
    """Whether the segment from ``point`` (on ``surface``) to the camera at ``eye`` is clear.

    Parameters
    ----------
    surface : pyvista.PolyData
    point, eye : (3,) float

    Returns
    -------
    bool
    """
    if not _has_faces(surface):
        return True
    if not surface.is_all_triangles:
        surface = surface.triangulate()
    P = np.asarray(surface.points, dtype=float)
    diag = float(np.linalg.norm(P.max(0) - P.min(0))) or 1.0
    q, eye = np.asarray(point, dtype=float).reshape(3), np.asarray(eye, dtype=float).reshape(3)
    to_eye = eye - q
    dist = float(np.linalg.norm(to_eye))
    if dist <= 1e-3 * diag:
        return True
    return not _Occluder(surface).blocked(q + 1e-3 * diag * to_eye / dist, eye)


def _surface_arrays(surface):
    P = np.asarray(surface.points, dtype=float)
    faces = np.asarray(surface.faces).reshape(-1, 4)
    return P, faces[:, 1:].astype(np.int64)


def _has_faces(surface):
    faces = getattr(surface, "faces", None)
    return faces is not None and np.asarray(faces).size > 0


def _outward_normal(P, F, target, radius):
    """Area-weighted normal of the triangles within ``radius`` of ``target``, pointing outwards.

    Outwards: the triangles' orientation is trusted when the surface encloses a positive
    volume; when it encloses a negative one (inward-facing triangles) the normal is flipped.
    """
    A, B, Cc = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    N = np.cross(B - A, Cc - A)  # twice the area times the unit normal
    cent = (A + B + Cc) / 3.0
    near = np.linalg.norm(cent - target, axis=1) <= radius
    if not near.any():
        near = np.argsort(np.linalg.norm(cent - target, axis=1))[:6]
    n = N[near].sum(axis=0)
    volume = np.einsum("ij,ij->", A, np.cross(B, Cc)) / 6.0
    if volume < 0:
        n = -n
    return _unit(n)


def _rotations(n, angles):
    """Directions at ``angles`` (radians) from ``n``, in four azimuths each."""
    n = _unit(n)
    u = _unit(np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0]))
    v = np.cross(n, u)
    out = []
    for a in angles:
        for w in (u, v, -u, -v):
            out.append(_unit(np.cos(a) * n + np.sin(a) * w))
    return out


def auto_view(surface, target, *, neighbours=None, focal=None):
    r"""A view direction from outside the shape that sees the point ``target``.

    Candidates, in order of preference: the outward normal at the target averaged over a
    neighbourhood (5% of the diagonal), its blend with the direction from the centre, the
    direction from the centre, the normal tilted by 25 and 50 degrees, for a point seen
    from less than about half of the directions (inside a concave region) the middle of
    the cone of directions it is seen from, the six principal
    directions of the shape and the eight diagonals of its principal frame
    (:func:`principal_axes`). Each candidate is scored by the fraction of the
    target's neighbourhood that a ray test shows unobstructed from the camera that
    ``reset_camera`` would place along it (the target itself weighing half); the first
    candidate with the best score wins.

    Parameters
    ----------
    surface : pyvista.PolyData
        The triangles drawn (the boundary of a volume).
    target : (3,) float or (k, 3) float
        The point to show (the source, or the minimum of the quantity drawn); with several
        points, the candidate view that sees most of them (facing them best) wins.
    neighbours : (k, 3) float, optional
        Points around the target that should be visible too; default the surface vertices
        within 3% of the diagonal (at most 12 of them).
    focal : (3,) float, optional
        The point the camera looks at (default the centre of the bounding box); the camera
        stays as far from it as from the centre, outside the whole shape.

    Returns
    -------
    direction : (3,) float
        Unit vector from the focal point towards the camera.
    visible : float
        Visibility score: 1/2 if the target is unobstructed, plus 1/2 times the fraction of
        its neighbours that are (1.0: everything seen).

    Examples
    --------
    Seeing the north pole of a sphere: from above.

    >>> from spectral_igl import viz
    >>> from spectral_igl.data_generators import icosphere
    >>> mesh, _ = viz.to_pyvista(icosphere(2))
    >>> direction, visible = viz.auto_view(mesh, [0.0, 0.0, 1.0])
    >>> bool(direction[2] > 0.5), visible
    (True, 1.0)
    """
    if not surface.is_all_triangles:
        surface = surface.triangulate()
    P, F = _surface_arrays(surface)
    target = np.asarray(target, dtype=float)
    if target.ndim == 2 and len(target) > 1:  # several features: all of them in view
        return _auto_view_many(surface, P, F, target)
    target = target.reshape(3)
    lo, hi = P.min(0), P.max(0)
    centre = (lo + hi) / 2.0
    focal = centre if focal is None else np.asarray(focal, dtype=float).reshape(3)
    diag = float(np.linalg.norm(hi - lo)) or 1.0
    radius = diag / 2.0 + float(np.linalg.norm(focal - centre))
    if len(F) == 0:
        return _unit(target - focal) if np.linalg.norm(target - focal) > 0 else _unit(VIEWS["iso"]), 1.0
    n = _outward_normal(P, F, target, 0.05 * diag)
    if neighbours is None:  # nearby vertices on the same side (not the back of a thin part)
        dist = np.linalg.norm(P - target, axis=1)
        close = np.argsort(dist)[:25]
        close = close[dist[close] <= 0.03 * diag]
        if close.size and np.linalg.norm(n) > 0:
            N = np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]])
            vn = np.zeros_like(P)
            for c in range(3):
                np.add.at(vn, F[:, c], N)
            sign = 1.0 if np.einsum("ij,ij->", P[F[:, 0]], np.cross(P[F[:, 1]], P[F[:, 2]])) >= 0 else -1.0
            close = close[sign * (vn[close] @ n) > 0][:12]
        neighbours = P[close]
    targets = np.vstack([target[None, :], np.asarray(neighbours, dtype=float).reshape(-1, 3)])
    out = target - centre
    occ = _Occluder(surface)
    eps = 1e-3 * diag
    cands = []
    if np.linalg.norm(n) > 0:
        cands.append(n)
        if np.linalg.norm(out) > 1e-9 * diag:
            cands.append(_unit(n + _unit(out)))
    if np.linalg.norm(out) > 1e-9 * diag:
        cands.append(_unit(out))
    if np.linalg.norm(n) > 0:
        cands += _rotations(n, np.radians([25.0, 50.0]))
    opening = _opening(occ, target, focal, radius, eps)
    if opening is not None:  # the middle of the cone the point is seen from (a mouth, a hole)
        cands.append(opening)
    cands += frame_directions(principal_axes(P, F)[1])
    best, best_score = cands[0], -1.0
    for d in cands:
        # the target itself counts as much as all its neighbours together
        s = 0.5 * visible_fraction(occ, targets[:1], focal, radius, d, eps)
        s += 0.5 * (visible_fraction(occ, targets[1:], focal, radius, d, eps) if len(targets) > 1
                    else 2.0 * s)
        # the point must also face the camera, not be seen edge-on through the rim
        if np.linalg.norm(n) > 0 and d @ n < 0.05:
            s *= 0.5
        if s > best_score + 1e-9:
            best, best_score = d, s
        if best_score >= 1.0:
            break
    return best, best_score


def _fibonacci_directions(k):
    """``k`` unit vectors spread evenly over the sphere."""
    i = np.arange(k) + 0.5
    z = 1.0 - 2.0 * i / k
    phi = np.pi * (1.0 + 5.0 ** 0.5) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def _opening(occ, target, focal, radius, eps, k=96):
    """Mean of the directions (of ``k`` spread over the sphere) from which ``target`` is seen.

    Inside a concave region (a mouth, the inner side of a handle) the outward normal often
    points at a wall; the middle of the cone of clear views looks straight in. ``None``
    when the target is seen from no direction, or from nearly every one (a convex tip:
    the normal is better then).
    """
    dirs = _fibonacci_directions(k)
    seen = np.array([visible_fraction(occ, target[None, :], focal, radius, d, eps) > 0 for d in dirs])
    if not seen.any() or seen.mean() > 0.45:
        return None
    m = dirs[seen].sum(axis=0)
    return _unit(m) if np.linalg.norm(m) > 1e-9 * seen.sum() else None


def _auto_view_many(surface, P, F, targets):
    """The candidate view that sees most of ``targets`` (k, 3), starting from their mean normal."""
    lo, hi = P.min(0), P.max(0)
    focal = (lo + hi) / 2.0
    diag = float(np.linalg.norm(hi - lo)) or 1.0
    normals = [_outward_normal(P, F, q, 0.05 * diag) for q in targets]
    n = _unit(np.sum(normals, axis=0))
    cands = ([n] if np.linalg.norm(n) > 0 else []) + [_unit(q - focal) for q in targets]
    if np.linalg.norm(n) > 0:
        cands += _rotations(n, np.radians([25.0, 50.0, 75.0]))
    span = targets.max(axis=0) - targets.min(axis=0)
    if np.linalg.norm(span) > 0:  # side views of the line between the features
        axis = _unit(targets[-1] - targets[0])
        cands += _rotations(axis, [np.pi / 2.0])
    cands += frame_directions(principal_axes(P, F)[1])
    occ = _Occluder(surface)
    best, best_score = cands[0], -1.0
    for d in cands:
        s = visible_fraction(occ, targets, focal, diag / 2.0, d, 1e-3 * diag)
        # a point seen edge-on hardly shows: prefer views that face every target; the worst
        # facing counts, so that two opposite features are seen from the side (with the
        # transition between them) rather than one of them alone
        s += 0.6 * float(min(d @ m for m in normals))
        if s > best_score + 1e-9:
            best, best_score = d, s
    return best, float(np.clip(best_score, 0.0, 1.0))


def place_camera(plotter, surface, camera="auto", target=None, focus=None, occluder=None):
    r"""Point ``plotter``'s camera at ``surface``.

    Parameters
    ----------
    plotter : pyvista.Plotter
    surface : pyvista.PolyData
        What is drawn (triangles; a point set is looked at from its centre).
    camera : see :func:`spectral_igl.viz.parse_view`
    target : (3,) float, optional
        The point to face with ``camera="auto"`` (the source or the feature drawn); without
        it ``"auto"`` looks at the broad side of the shape, along a diagonal of its
        principal frame (:func:`principal_axes`).
    focus : (k, 3) float, optional
        The points to frame (the source's component of a shape with several); default every
        vertex of a cell of ``surface``. The camera looks at their centre from outside the
        whole shape.
    occluder : pyvista.PolyData, optional
        The triangles that can hide the target (default ``surface``).

    Returns
    -------
    dict
        ``direction`` and ``up`` (unit vectors), ``visible`` (fraction of the target's
        neighbourhood seen; ``None`` when not tested), ``points`` (those to frame).

    Examples
    --------
    >>> import pyvista as pv
    >>> from spectral_igl import viz
    >>> from spectral_igl.data_generators import icosphere
    >>> mesh, _ = viz.to_pyvista(icosphere(2))
    >>> plotter = pv.Plotter(off_screen=True)
    >>> _ = plotter.add_mesh(mesh)
    >>> view = viz.place_camera(plotter, mesh, "+z")
    >>> view["direction"].round(6).tolist()
    [0.0, 0.0, 1.0]
    >>> plotter.close()
    """
    mode, value = parse_view(camera)
    if mode == "pyvista":
        plotter.camera_position = value
        plotter.reset_camera()
        return {"direction": None, "up": None, "visible": None}
    P = np.asarray(surface.points, dtype=float)
    F = None
    used = P
    if _has_faces(surface):
        tri = surface if surface.is_all_triangles else surface.triangulate()
        F = _surface_arrays(tri)[1]
        used = np.asarray(tri.points)[np.unique(F)]
    lo, hi = P.min(0), P.max(0)
    centre = (lo + hi) / 2.0
    if focus is not None:
        used = np.asarray(focus, dtype=float).reshape(-1, 3)
    focal = (used.min(0) + used.max(0)) / 2.0 if len(used) else centre
    radius = max(float(np.linalg.norm(hi - lo)) / 2.0, 1e-12) + float(np.linalg.norm(focal - centre))
    visible = None
    if mode == "direction":
        d = value
    elif target is None:
        axes = principal_axes(P, F)[1]
        front = axes[2] * (1.0 if axes[2][int(np.argmax(np.abs(axes[2])))] >= 0 else -1.0)
        d = _unit(front + 0.4 * _sign_up(axes[1]) + 0.25 * _sign_up(axes[0]))
    elif F is None:
        out = np.mean(np.atleast_2d(np.asarray(target, dtype=float)), axis=0) - focal
        d = _unit(out) if np.linalg.norm(out) > 0 else _unit(VIEWS["iso"])
        d = _unit(d + 0.3 * _unit(VIEWS["iso"]))
    else:
        d, visible = auto_view(surface if occluder is None else occluder, target,
                               focal=focal if focus is not None else None)
    up = up_direction(P if F is not None else used, d, F)  # the whole shape's axes, also for a part
    dist = camera_distance(radius)
    plotter.camera_position = [tuple(focal + dist * d), tuple(focal), tuple(up)]
    plotter.reset_camera_clipping_range()
    return {"direction": d, "up": up, "visible": visible, "points": used}


def fit_view(plotter, points, height=0.8, width=0.92, lift=0.0):
    """Narrow the camera's view angle until ``points`` fill ``height`` x ``width`` of the picture.

    The camera keeps its position and direction; the focal point moves sideways so that the
    points are centred (``lift``: fraction of the picture height to move them up, to leave
    room for a colour bar at the bottom).
    """
    cam = plotter.camera
    eye = np.asarray(cam.position, dtype=float)
    focal = np.asarray(cam.focal_point, dtype=float)
    fwd = _unit(focal - eye)
    up = _unit(np.asarray(cam.up, dtype=float) - (np.asarray(cam.up, dtype=float) @ fwd) * fwd)
    right = np.cross(fwd, up)
    Q = np.asarray(points, dtype=float) - eye
    depth = Q @ fwd
    if len(Q) == 0 or np.any(depth <= 0):
        return
    x, y = (Q @ right) / depth, (Q @ up) / depth  # tangents of the angles to the axis
    cx, cy = (x.max() + x.min()) / 2.0, (y.max() + y.min()) / 2.0
    w, h = plotter.window_size
    aspect = w / max(h, 1)
    half = max((y.max() - y.min()) / 2.0 / height, (x.max() - x.min()) / 2.0 / width / aspect, 1e-9)
    dist = float(np.linalg.norm(focal - eye))
    cy -= lift * 2.0 * half
    new_focal = eye + dist * _unit(fwd + cx * right + cy * up)
    cam.focal_point = tuple(new_focal)
    cam.up = tuple(up)
    cam.view_angle = float(np.degrees(2.0 * np.arctan(half)))
