"""Machine-readable benchmark results, shared by the benchmark scripts (run as
``python benchmarks/<script>.py``, which puts this folder on the import path).

A script that prints a table of ``docs/results.md`` also writes it, with ``--json-dir DIR``,
to ``DIR/<table>.json``:

.. code-block:: json

    {"table": "ordering", "command": "OPENBLAS_NUM_THREADS=1 python benchmarks/ordering.py",
     "date": "2026-11-26", "machine": {"cpu": "...", "cores": 2, "load_average": [...], ...},
     "provenance": "printed by the command", "columns": [...], "rows": [[...], ...]}

``benchmarks/results.py`` renders ``docs/results.md`` from these files.
"""
from __future__ import annotations

import datetime
import json
import os
import platform
import shlex
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"


def cpu_model() -> str:
    """The processor's model name from ``/proc/cpuinfo`` (or what ``platform`` says)."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine() -> dict:
    """What the numbers depend on: processor, cores, system, Python, numpy, BLAS threads, load."""
    import numpy
    import scipy

    load = [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "system": f"{platform.system()} {platform.release()}",
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "openblas_num_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
        "load_average": load,
    }


def command(argv: list[str] | None = None) -> str:
    """The command line that ran this script, from the repository root, without ``--json-dir DIR``."""
    argv = list(sys.argv if argv is None else argv)
    script = Path(argv[0]).resolve()
    rest, skip = [], False
    for a in argv[1:]:
        if skip:
            skip = False
        elif a == "--json-dir":
            skip = True
        elif not a.startswith("--json-dir="):
            rest.append(a)
    try:
        script = script.relative_to(ROOT)
    except ValueError:
        pass
    env = "OPENBLAS_NUM_THREADS=1 " if os.environ.get("OPENBLAS_NUM_THREADS") == "1" else ""
    return env + shlex.join(["python", script.as_posix(), *rest])


def markdown_row(cells) -> str:
    return "| " + " | ".join(str(c) for c in cells) + " |"


def print_header(columns) -> None:
    """Print a markdown table's header (the rows follow as they are measured)."""
    print(markdown_row(columns))
    print("|" + "---|" * len(columns), flush=True)


def write(json_dir, table: str, columns, rows) -> Path:
    """Write ``rows`` (lists of display strings) under ``columns`` to ``json_dir/<table>.json``."""
    path = Path(json_dir) / f"{table}.json"
    data = {
        "table": table,
        "command": command(),
        "date": datetime.date.today().isoformat(),
        "machine": machine(),
        "provenance": "printed by the command",
        "columns": [str(c) for c in columns],
        "rows": [[str(c) for c in row] for row in rows],
    }
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
    return path


class Table:
    """A markdown table printed row by row and, given a path, written as JSON at the end.

    Parameters
    ----------
    name : str
        The table's name in ``docs/results`` (``docs/results/<name>.json``).
    columns : list of str
        Column headers.
    json_dir : str or Path or None
        The folder of the JSON file (``docs/results``); None writes nothing.
    """

    def __init__(self, name: str, columns, json_dir=None):
        self.name, self.columns, self.json_dir, self.rows = name, list(columns), json_dir, []
        print_header(self.columns)

    def add(self, *cells) -> None:
        """Print one row and keep it."""
        row = [str(c) for c in cells]
        if len(row) != len(self.columns):
            raise ValueError(f"row has {len(row)} cells, the table {len(self.columns)} columns")
        self.rows.append(row)
        print(markdown_row(row), flush=True)

    def close(self) -> None:
        """Write the JSON file, when a path was given."""
        if self.json_dir:
            print(f"(written to {write(self.json_dir, self.name, self.columns, self.rows)})")
