"""One way in: every public function that takes a Laplacian also takes what a user has.

The rule, applied by :func:`as_laplacian` at every public entry point:

* a :class:`Laplacian` is used as it is (build it once with :func:`spectral_igl.laplacian`
  and reuse it: it caches factorizations and spectral bounds across calls);
* a pair ``(V, F)`` (triangles) or ``(V, T)`` (tetrahedra), as a tuple or a list, becomes
  ``spectral_igl.laplacian(V, F)`` with its defaults;
* a pyvista ``PolyData``/``UnstructuredGrid``, a ``trimesh.Trimesh`` or a ``meshio.Mesh``
  becomes ``spectral_igl.laplacian`` of its triangles or tetrahedra (polygons are
  fan-triangulated); one without cells (``trimesh.PointCloud``, a pyvista point set) becomes
  :func:`spectral_igl.point_cloud_laplacian` of its points.

Anything else is refused with a ``TypeError`` that says which of these to pass; a bare
``(n, 3)`` array is refused too (a point cloud or half of a mesh? pass
``point_cloud_laplacian(P)`` or ``(V, F)``).
"""
from __future__ import annotations

import numpy as np

from .._validate import as_mesh_arrays, describe, is_mesh_object
from ._operator import Laplacian
from .mesh import laplacian, triangle_arrays
from .points import point_cloud_laplacian

__all__ = ["as_laplacian", "as_laplacian_or_triangles"]


def as_laplacian(x, name: str = "lap", **options) -> Laplacian:
    r"""A :class:`Laplacian` from a Laplacian, a ``(V, F)``/``(V, T)`` pair or a mesh object.

    Parameters
    ----------
    x : Laplacian, tuple or mesh
        A Laplacian (returned as it is), a ``(V, F)`` triangle or ``(V, T)`` tetrahedral pair
        of arrays, or a pyvista/trimesh/meshio mesh, built with the defaults of
        :func:`spectral_igl.laplacian`.
    name : str
        The argument's name in error messages.
    **options
        Keyword arguments of :func:`spectral_igl.laplacian` (``weights``, ``mass``...) used
        when ``x`` is a mesh with cells; a Laplacian is returned as it is, and a point cloud
        (a mesh object without cells) gets :func:`spectral_igl.point_cloud_laplacian`'s
        defaults.

    Returns
    -------
    Laplacian

    Raises
    ------
    TypeError
        For anything else, naming the argument and what it received.

    Examples
    --------
    >>> import numpy as np
    >>> import spectral_igl as sig
    >>> from spectral_igl.data_generators import icosphere
    >>> from spectral_igl.laplacian import as_laplacian
    >>> V, F = icosphere(1)
    >>> lap = as_laplacian((V, F))
    >>> lap.n, as_laplacian(lap) is lap
    (42, True)
    >>> as_laplacian((V, F), mass="full").lumped
    False
    """
    out = _laplacian_or_arrays(x, name)
    return laplacian(*out, **options) if isinstance(out, tuple) else out


def as_laplacian_or_triangles(x, name: str = "lap"):
    """:func:`as_laplacian`, except that a triangle mesh comes back as its arrays ``(V, F)``,
    validated and cleaned as :func:`spectral_igl.laplacian` reads them
    (:func:`~spectral_igl.laplacian.mesh.triangle_arrays`), and no Laplacian is built.

    For callers that build their own operators on a triangle mesh given as arrays or as a
    mesh object; a Laplacian, a tetrahedral or polygon mesh and a point cloud come back as
    :func:`as_laplacian` returns them.

    Examples
    --------
    >>> from spectral_igl.data_generators import icosphere
    >>> V, F = icosphere(1)
    >>> Vc, Fc = as_laplacian_or_triangles((V, F))
    >>> Fc.shape, type(as_laplacian_or_triangles(as_laplacian((V, F)))).__name__
    ((80, 3), 'Laplacian')
    """
    out = _laplacian_or_arrays(x, name)
    if not isinstance(out, tuple):
        return out
    return triangle_arrays(*out, stacklevel=3) or laplacian(*out)


def _laplacian_or_arrays(x, name: str):
    """``x`` itself (a Laplacian), a point-cloud Laplacian, or the ``(V, C)`` arrays of a mesh."""
    if isinstance(x, Laplacian):
        return x
    if isinstance(x, (tuple, list)) and len(x) == 2:
        return tuple(x)
    if is_mesh_object(x):
        V, C = as_mesh_arrays(x, name=name, need_cells=False)
        if C is None:
            return point_cloud_laplacian(V)
        return V, C
    hint = ""
    if isinstance(x, np.ndarray) and x.ndim == 2:
        hint = (" (an array alone is ambiguous: pass (V, F) as one tuple for a mesh, or "
                "sig.point_cloud_laplacian(P) for points)")
    raise TypeError(f"{name} must be a spectral_igl.Laplacian, a (V, F) or (V, T) pair, or a "
                    f"pyvista/trimesh/meshio mesh; got {describe(x)}{hint}")
