"""docs/results.md is what benchmarks/results.py renders from the benchmarks' stored JSON.

Every table on the page comes from ``docs/results/<name>.json`` and says its command, date and
machine, so the page and the measurements cannot drift apart.
"""
from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results"


def results_module():
    spec = importlib.util.spec_from_file_location("benchmark_results", ROOT / "benchmarks" / "results.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_the_page_is_the_rendering_of_the_stored_results():
    r = results_module()
    assert (ROOT / "docs" / "results.md").read_text(encoding="utf-8") == r.render(), \
        "docs/results.md differs from its rendering: run python benchmarks/results.py"


def test_every_table_says_command_date_and_machine():
    r = results_module()
    names = r.table_names()
    stored = sorted(p.stem for p in RESULTS.glob("*.json"))
    assert sorted(names) == stored                       # no table without JSON, no JSON unused
    page = (ROOT / "docs" / "results.md").read_text(encoding="utf-8")
    tables = re.findall(r"^\s*\|---", page, flags=re.M)
    captions = re.findall(r"^\s*\*Command:\* `[^`]+`.*\*Date:\* (\d{4}-\d\d-\d\d).*\*Machine:\* \S", page, flags=re.M)
    assert len(tables) == len(captions) == len(names)
    for name in names:
        data = json.loads((RESULTS / f"{name}.json").read_text(encoding="utf-8"))
        assert re.fullmatch(r"\d{4}-\d\d-\d\d", data["date"])
        assert all(c.split()[0] in ("python", "OPENBLAS_NUM_THREADS=1") for c in r.commands(data))
        if data["provenance"] == r.MEASURED:                 # written by the benchmark itself
            m = data["machine"]
            assert m["cpu"] and m["cores"] >= 1 and len(m["load_average"]) == 3
            assert "--json-dir" not in data["command"]
        else:                                                # an older table says it was not rerun
            assert "not re-run" in data["provenance"] and data["machine"]["description"]


def test_a_benchmark_table_round_trips(tmp_path, capsys):
    """What a benchmark prints is what it stores, and what the page shows."""
    import sys

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from _results import Table

    t = Table("demo", ["mesh", "n", "error"], tmp_path)
    t.add("cow.obj", "2,903", "1.0e-12")
    with pytest.raises(ValueError, match="2 cells"):
        t.add("spot.obj", "2,930")
    t.close()
    printed = capsys.readouterr().out
    data = results_module().load("demo", tmp_path)
    rendered = results_module().render_table(data)
    assert rendered[2:] == printed.splitlines()[:3]
    assert rendered[0].startswith("*Command:* `") and data["date"] in rendered[0]
