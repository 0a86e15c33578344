"""The package's layout: data flows one way through its stages.

Every module of ``spectral_igl`` imports only from its own stage or the stages before it,
never through the package root, never a private name of another module, and its imports
have no cycle. Imports are read at every depth: an import inside a function is an edge like
one at the top of the module (it only runs later, but the two modules still depend on each
other). A new module gets a stage in :data:`STAGES`; a new import of another project inside
a function gets a line in :data:`LAZY_EXTRAS`.
"""
from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1] / "spectral_igl"

#: first dotted component below ``spectral_igl`` -> stage (lower imports nothing higher)
STAGES = {
    "_validate": 0, "_version": 0, "_extras": 0, "io": 0, "progress": 0, "accuracy": 0,
    "laplacian": 1, "data_generators": 1,
    "filters": 2,
    "linalg": 3,
    "approx": 4,
    "families": 5,
    "diagonal": 6,
    "kernels": 7, "local": 7,
    "distances": 8, "descriptors": 8, "embedding": 8,
    "applications": 9,
    "quantity": 10,
    "collection": 11, "retrieval": 11,
    "viz": 12,
    "cli": 13,
}
#: compiled halves of a module, imported by that module alone
EXTENSIONS = {"laplacian._assembly": {"laplacian.anisotropic", "laplacian.points", "laplacian.intrinsic"},
              "linalg._ldlt": {"linalg.ldlt"}}
#: other projects imported inside functions, by top-level name, and why not at the top
LAZY_EXTRAS = {
    "pyvista": "optional extra 'viz'", "vtkmodules": "optional extra 'viz' (pyvista's VTK)",
    "matplotlib": "optional extra 'viz'", "PIL": "optional extra 'viz' (matplotlib's imaging)",
    "pypardiso": "optional extra 'fast'",
    "pytetwild": "only tetrahedralize() needs it, and it is slow to import",
    "meshio": "only formats libigl does not read",
    "distributed": "only a collection run on a cluster", "zarr": "only a collection's store",
    "dask": "only a local cluster's worker settings (distributed's own dependency)",
    "tqdm": "only a requested progress bar",
    "IPython": "only a plot displayed by IPython (a notebook), which is running",
    "cholespy": "a factorization back end chosen at run time",
    "pymetis": "a fill-reducing ordering chosen at run time",
    "igl": "keeps `import spectral_igl` quick; the functions that assemble need it",
    "scipy": "submodules (spatial, optimize, interpolate, special, ...) only the functions use",
    "numpy": "numpy.polynomial, and re-imports in functions that run on their own",
    "data_generators": "the command line's demo meshes, shipped beside the package",
}


def _modules(root: Path = ROOT):
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root).with_suffix("")
        parts = list(rel.parts)
        is_pkg = parts[-1] == "__init__"
        if is_pkg:
            parts = parts[:-1]
        yield ".".join(parts), path, is_pkg


def _imports(name: str, path: Path, is_pkg: bool):
    """(target module below spectral_igl, imported names, line, top-level?) for each import."""
    tree = ast.parse(path.read_text(), str(path))
    top = set(id(n) for n in tree.body)
    package = name.split(".") if is_pkg else name.split(".")[:-1]
    package = [p for p in package if p]
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0:
                if node.module and node.module.startswith("spectral_igl"):
                    target = node.module[len("spectral_igl"):].lstrip(".")
                else:
                    continue
            else:
                base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
                target = ".".join(base + ([node.module] if node.module else []))
            yield target, [a.name for a in node.names], node.lineno, id(node) in top
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("spectral_igl"):
                    yield a.name[len("spectral_igl"):].lstrip("."), [], node.lineno, id(node) in top


def _stage(module: str) -> int:
    head = module.split(".")[0]
    if head not in STAGES:
        pytest.fail(f"module spectral_igl.{module} has no stage: add {head!r} to STAGES in {__file__}")
    return STAGES[head]


MODULES = list(_modules())


@pytest.mark.parametrize("name,path,is_pkg", MODULES, ids=[m[0] or "__init__" for m in MODULES])
def test_imports_flow_one_way(name, path, is_pkg):
    if name == "":
        return        # the package root gathers the public names of every stage
    own = _stage(name)
    for target, names, line, _ in _imports(name, path, is_pkg):
        where = f"{path.relative_to(ROOT.parent)}:{line}"
        assert target != "", f"{where} imports {names} through the package root"
        if target in EXTENSIONS or any(f"{target}.{n}" in EXTENSIONS for n in names):
            ext = target if target in EXTENSIONS else next(f"{target}.{n}" for n in names
                                                           if f"{target}.{n}" in EXTENSIONS)
            assert name in EXTENSIONS[ext], f"{where}: only {EXTENSIONS[ext]} may import {ext}"
            continue
        assert _stage(target) <= own, f"{where}: stage {own} module imports the later stage {target}"
        private = [n for n in names if n.startswith("_") and n != "__version__"]
        assert not private, f"{where} imports the private names {private} of spectral_igl.{target}"
        if target.split(".")[-1].startswith("_") and target.split(".")[0] != name.split(".")[0]:
            assert target in ("_validate", "_version", "_extras"), \
                f"{where} imports the private module spectral_igl.{target} from another room"


def _known(modules) -> set[str]:
    return {m[0] for m in modules} | set(EXTENSIONS)


def import_graph(modules) -> dict[str, dict[str, tuple[int, bool]]]:
    """module -> {imported module: (line, top-level?)}, imports at every depth.

    ``from .x import y`` counts as an edge to the module ``x.y`` when that is a module,
    else to ``x``; a package's ``__init__`` is a module like the others.
    """
    known = _known(modules)
    graph = {}
    for name, path, is_pkg in modules:
        deps = {}
        for target, names, line, top in _imports(name, path, is_pkg):
            for cand in [f"{target}.{n}" for n in names] + [target]:
                if cand in known and cand != name:
                    deps.setdefault(cand, (line, top))
                    break
        graph[name] = deps
    return graph


def find_cycle(graph) -> list[str] | None:
    """One import cycle of ``graph`` as a closed path, or None.

    The package root is left out: it gathers every stage's public names, and no module
    imports through it. A room's ``__init__`` is not: importing any of its submodules runs
    it first, so its imports are edges like any others.
    """
    state, stack = {}, []

    def visit(u):
        state[u] = 1
        stack.append(u)
        for v in graph.get(u, ()):
            if not v:
                continue
            if state.get(v) == 1:
                return stack[stack.index(v):] + [v]
            if state.get(v) is None:
                found = visit(v)
                if found:
                    return found
        stack.pop()
        state[u] = 2
        return None

    for u in graph:
        if u and state.get(u) is None:
            found = visit(u)
            if found:
                return found
    return None


def _describe(graph, cycle) -> str:
    steps = []
    for u, v in zip(cycle, cycle[1:]):
        line, top = graph[u][v]
        steps.append(f"spectral_igl.{u}:{line}{'' if top else ' (inside a function)'} -> {v}")
    return "import cycle: " + ", ".join(steps)


def test_no_import_cycle():
    graph = import_graph(MODULES)
    cycle = find_cycle(graph)
    assert cycle is None, _describe(graph, cycle)


def test_lazy_imports_of_other_projects_are_named():
    stdlib = sys.stdlib_module_names
    for name, path, is_pkg in MODULES:
        tree = ast.parse(path.read_text(), str(path))
        top = set(id(n) for n in tree.body)
        for node in ast.walk(tree):
            if id(node) in top or not isinstance(node, (ast.Import, ast.ImportFrom)):
                continue
            if isinstance(node, ast.ImportFrom):
                heads = [] if node.level else [node.module.split(".")[0]]
            else:
                heads = [a.name.split(".")[0] for a in node.names]
            for head in heads:
                if head != "spectral_igl" and head not in stdlib:
                    assert head in LAZY_EXTRAS, (f"{path.relative_to(ROOT.parent)}:{node.lineno} imports "
                                                 f"{head} inside a function: name it in LAZY_EXTRAS")


#: scratch packages with one cycle each: module-level, inside a function (relative and
#: absolute), through a package's __init__, and a clean one
SCRATCH = {
    "top-level": ({"a.py": "from .b import g\n", "b.py": "from .a import f\n"}, True),
    "in-function": ({"a.py": "def f():\n    from .b import g\n",
                     "b.py": "def g():\n    if True:\n        from .a import f\n"}, True),
    "absolute-in-method": ({"a.py": "import spectral_igl.b\n",
                            "b.py": "class K:\n    def m(self):\n        import spectral_igl.a\n"}, True),
    "through-init": ({"room/__init__.py": "from .x import f\n",
                      "room/x.py": "def f():\n    from ..y import g\n",
                      "y.py": "def g():\n    from .room import f\n"}, True),
    "downward": ({"room/__init__.py": "from .x import f\n", "room/x.py": "def f():\n    from ..y import g\n",
                  "y.py": "def g():\n    pass\n"}, False),
}


@pytest.mark.parametrize("kind", list(SCRATCH))
def test_scan_finds_a_scratch_cycle_of_each_kind(tmp_path, kind):
    files, cyclic = SCRATCH[kind]
    root = tmp_path / "spectral_igl"
    for rel, text in {"__init__.py": "", **files}.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    cycle = find_cycle(import_graph(list(_modules(root))))
    assert (cycle is not None) == cyclic, cycle


@pytest.mark.parametrize("name,path", [(m[0], m[1]) for m in MODULES if m[2]],
                         ids=[m[0] or "__init__" for m in MODULES if m[2]])
def test_package_roots_only_gather_names(name, path):
    """A room's ``__init__`` holds its docstring, imports and ``__all__``: the machinery lives
    in named modules, where a reader opening the room finds it."""
    tree = ast.parse(path.read_text(), str(path))
    for k, node in enumerate(tree.body):
        if k == 0 and isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            continue
        targets = node.targets if isinstance(node, ast.Assign) else \
            [node.target] if isinstance(node, ast.AugAssign) else []
        assert [getattr(t, "id", None) for t in targets] == ["__all__"], \
            f"{path.relative_to(ROOT.parent)}:{node.lineno} holds more than imports and __all__"
