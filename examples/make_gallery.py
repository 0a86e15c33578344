"""Run the figure scripts and copy a selection of their images, compressed, to docs/gallery/.

    python examples/make_gallery.py [--quick] [--out figures/] [--only fig07 fig15] [--copy-only]
"""
from __future__ import annotations

import argparse
import shutil
from pathlib import Path

import _common as C

GALLERY = C.ROOT / "docs" / "gallery"
PICKS = ["fig09_distances.png", "fig02_harmonic_6.png", "fig03_eigenfunction_10.png",
         "fig04_anisotropic_heat.png", "fig05_volumetric_smoothing.png",
         "fig08_volumetric_heat_kernel.png", "fig12_biharmonic_stability.png",
         "fig18_23_robustness.png", "fig24_smoothing.png", "fig15_truncated_kernel.png",
         "fig15_gibbs.png", "fig13_error_vs_k.png", "fig07_17_time_vs_n.png",
         "fig16_accuracy_vs_time.png", "fig05_lcurve.png", "fig10_filters.png",
         "fig_retrieval_matrix.png", "fig_retrieval_neighbours.png", "fig_correspondence.png",
         "fig_correspondence_error.png"]
MAX_BYTES = 150_000


def compress(src, dst):
    """Copy ``src`` to ``dst``; when over MAX_BYTES, a 256-colour octree palette with dithering.

    The octree palette keeps the whole hue circle of the colour bars (a median-cut palette
    drops rare hues); the image is downscaled only if the palette is still too large.
    """
    from PIL import Image

    shutil.copyfile(src, dst)
    scale = 1.0
    while dst.stat().st_size > MAX_BYTES and scale > 0.3:
        img = Image.open(src).convert("RGB")
        if scale < 1.0:
            img = img.resize((int(img.width * scale), int(img.height * scale)), Image.LANCZOS)
        img.quantize(colors=256, method=Image.Quantize.FASTOCTREE,
                     dither=Image.Dither.FLOYDSTEINBERG).save(dst, optimize=True)
        scale *= 0.85


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--out", default="figures")
    p.add_argument("--only", nargs="+", metavar="NAME",
                   help="only run these scripts (e.g. fig07 fig15); the others' images are reused")
    p.add_argument("--copy-only", action="store_true",
                   help="run no script: copy the images already in --out")
    args = p.parse_args(argv)
    from spectral_igl.cli import main as cli

    if not args.copy_only:
        code = cli(["figures", "--out", args.out] + (["--quick"] if args.quick else [])
                   + (["--only", *args.only] if args.only else []))
        if code != 0:
            raise SystemExit(code)
    GALLERY.mkdir(parents=True, exist_ok=True)
    for name in PICKS:
        src = Path(args.out) / name
        if not src.is_file():
            print(f"{src}: missing (not copied)")
            continue
        compress(src, GALLERY / name)
        print(f"{GALLERY / name}: {(GALLERY / name).stat().st_size // 1000} KB")


if __name__ == "__main__":
    main()
