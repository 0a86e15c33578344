"""Pictures in Jupyter: docs/notebooks/first_steps.ipynb runs in a kernel and shows its plots inline.

A cell that ends with ``viz.plot_levelsets(...)`` must display a picture (pyvista's static
backend: a PNG; an interactive backend: its widget), not the plotter's repr, and the plotter
stays what scripts use.
"""
from __future__ import annotations

import base64
import io
from pathlib import Path

import numpy as np
import pytest
from _needs import VIZ, needs

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOK = ROOT / "docs" / "notebooks" / "first_steps.ipynb"

pytestmark = [VIZ, pytest.mark.usefixtures("one_blas_thread")]


def picture_stats(png: bytes):
    """(pixel standard deviation, distinct colours, (height, width)) of a PNG."""
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    return float(img.std()), len(np.unique(img.reshape(-1, 3), axis=0)), img.shape[:2]


def shape():
    from spectral_igl.data_generators import icosphere

    V, F = icosphere(2)
    return V, F


@needs("nbclient", "nbformat", "ipykernel")
def test_first_steps_notebook_runs_and_shows_its_pictures(tmp_path, monkeypatch):
    import nbclient
    import nbformat

    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    monkeypatch.setenv("PYTHONPATH", str(ROOT))          # the kernel imports this checkout
    nb = nbformat.read(NOTEBOOK, as_version=4)
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    pngs = [base64.b64decode(o.data["image/png"]) for o in outputs if "image/png" in o.get("data", {})]
    assert len(pngs) == 2, [o.get("data", {}).keys() for o in outputs]       # the two plots, inline
    for png in pngs:
        std, colours, (h, w) = picture_stats(png)
        assert std > 8 and colours > 40 and (h, w) == (320, 480), (std, colours, (h, w))
    text = " ".join(o.get("text", "") for o in outputs)
    assert "bound kind: proof" in text
    # the stored notebook (rendered by the documentation without running it) has them too
    stored = nbformat.read(NOTEBOOK, as_version=4)
    assert sum("image/png" in o.get("data", {}) for c in stored.cells if c.cell_type == "code"
               for o in c.outputs) == 2


@needs("nbclient", "nbformat", "ipykernel", "trame_pyvista")
def test_the_interactive_backend_shows_a_widget(tmp_path, monkeypatch):
    """With pyvista's interactive backend (trame, ``pip install "pyvista[jupyter]"``) the same
    cell shows pyvista's widget instead of a PNG."""
    import nbclient
    import nbformat

    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "1")
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(
        "import pyvista as pv\n"
        "import spectral_igl as sig\n"
        "from spectral_igl import viz\n"
        "from spectral_igl.data_generators import icosphere\n"
        "pv.set_jupyter_backend('trame')\n"
        "V, F = icosphere(2)\n"
        "k = sig.heat_kernel(sig.laplacian(V, F), 1e-2, 0)"),
        nbformat.v4.new_code_cell("viz.plot_levelsets((V, F), k, window_size=(320, 240))")]
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    out = nb.cells[1].outputs
    assert not [o for o in out if o.output_type == "error"]
    data = [o.get("data", {}) for o in out if o.output_type == "display_data"]
    assert any("application/vnd.jupyter.widget-view+json" in d for d in data), data
    assert not any("Plotter" in d.get("text/plain", "") for d in data)     # not the repr


def test_a_written_picture_is_the_plotters_png(tmp_path):
    """With ``filename=`` the plotter is closed; it still shows the picture it wrote."""
    from PIL import Image

    from spectral_igl.viz import plot_levelsets

    V, F = shape()
    out = tmp_path / "f.png"
    p = plot_levelsets((V, F), V[:, 0], off_screen=True, window_size=(240, 160), filename=out)
    png = p._repr_png_()                                   # what IPython shows
    assert png is not None
    shown = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    written = np.asarray(Image.open(out).convert("RGB"))
    assert np.array_equal(shown, written)
    assert callable(getattr(p, "_ipython_display_", None))


def test_an_open_plotter_stays_a_plotter():
    """Scripts keep using the returned plotter: screenshots, more actors, show()."""
    from spectral_igl.viz import plot_levelsets

    V, F = shape()
    p = plot_levelsets((V, F), V[:, 0], off_screen=True, window_size=(240, 160))
    assert callable(getattr(p, "_ipython_display_", None))
    img = p.screenshot(return_img=True)
    assert img.shape[:2] == (160, 240) and float(img.std()) > 8
    p.close()
