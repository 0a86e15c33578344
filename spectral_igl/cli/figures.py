"""The ``figures`` job: run the example scripts that draw the survey's figures."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from ..progress import progress_bar
from .arguments import progress_arg, quiet_arg
from .errors import EXIT_ERROR, EXIT_OK, EXIT_USAGE, CLIError
from .outputs import say

__all__ = ["add_figures", "examples_dir", "run_figures"]


def add_figures(sub):
    """The ``figures`` job's arguments."""
    p = sub.add_parser("figures", help="run the example scripts that draw the survey's figures",
                       description="Run the scripts in examples/ (a source checkout) and write "
                                   "their PNGs to --out.")
    p.add_argument("-o", "--out", default="figures", help="output directory (default figures/)")
    p.add_argument("--quick", action="store_true", help="small shapes, fast (seconds per figure)")
    p.add_argument("--only", nargs="+", metavar="NAME", help="only these scripts (e.g. fig02 fig09)")
    p.add_argument("--list", action="store_true", help="list the scripts and exit")
    p.add_argument("--mesh", help="run the scripts on this mesh instead of generated shapes")
    quiet_arg(p)
    progress_arg(p)


def examples_dir():
    """The ``examples/`` directory of a source checkout, or None."""
    here = Path(__file__).resolve().parents[2] / "examples"
    env = os.environ.get("SPECTRAL_IGL_EXAMPLES")
    for d in ([Path(env)] if env else []) + [here, Path.cwd() / "examples"]:
        if (d / "_common.py").is_file():
            return d
    return None


def run_figures(args):
    """Run the chosen ``examples/fig*.py``; a failing script is reported and the others go on."""
    import importlib.util

    d = examples_dir()
    if d is None:
        raise CLIError("the example scripts were not found: run from a source checkout "
                       "(or set SPECTRAL_IGL_EXAMPLES to its examples/ directory)", EXIT_ERROR)
    scripts = sorted(p for p in d.glob("fig*.py"))
    names = [p.stem for p in scripts]
    if args.list:
        print("\n".join(names))
        return EXIT_OK
    if args.only:
        unknown = [n for n in args.only if not any(m == n or m.startswith(n + "_") for m in names)]
        if unknown:
            raise CLIError(f"unknown figure script(s) {', '.join(unknown)}; available: "
                           f"{', '.join(names)}", EXIT_USAGE)
        scripts = [p for p in scripts if any(p.stem == n or p.stem.startswith(n + "_") for n in args.only)]
    sys.path.insert(0, str(d))
    prog = progress_bar(len(scripts), "figures", unit="figure")
    failed = []
    for p in scripts:
        spec = importlib.util.spec_from_file_location(p.stem, p)
        mod = importlib.util.module_from_spec(spec)
        argv = ["--out", str(args.out)] + (["--quick"] if args.quick else [])
        argv += ["--mesh", args.mesh] if args.mesh else []
        try:
            spec.loader.exec_module(mod)
            mod.main(argv)  # prints its own summary
        except Exception as err:  # report and go on with the other figures
            failed.append(p.stem)
            print(f"{p.stem}: failed: {type(err).__name__}: {err}", file=sys.stderr)
        prog.set_postfix_str(p.stem)
        prog.update()
    prog.close()
    if failed:
        print(f"{len(failed)} of {len(scripts)} figure script(s) failed: {', '.join(failed)}",
              file=sys.stderr)
        return EXIT_ERROR
    say(args, f"wrote the figures of {len(scripts)} script(s) to {args.out}")
    return EXIT_OK
