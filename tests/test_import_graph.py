"""No import cycles in the package, lazy (function-level) imports included.

The graph is built from the source with :mod:`ast`: every ``import mftire...`` and
``from mftire... import ...`` (absolute or relative, at any nesting level) is an edge to
the module it names (``from pkg import name`` goes to ``pkg.name`` when that is a
module, else to ``pkg/__init__``).  Importing ``a.b.c`` also runs ``a/b/__init__``, so
edges to the sub-package ``__init__`` files on the way are added as well.

Two checks: no cycle between modules, and no cycle between the layers (each
sub-package, e.g. ``mftire.fitting``, and each top-level module counts as one node):
``fitting.bands`` importing ``compare.data`` while ``compare.data`` imports
``fitting.data`` is a cycle of the second kind.

The root ``mftire/__init__`` is left out on purpose: it re-exports the public API
(``Tyre``, ``read_tir`` ...), and Python runs it before any ``mftire.x``, so every module
would be "in a cycle" with it.  That is harmless only as long as no module inside the
package imports names from the root package; the last test checks exactly that.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mftire"


def _modules() -> dict[str, Path]:
    out = {}
    for p in PACKAGE.rglob("*.py"):
        parts = list(p.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


MODULES = _modules()


def _resolve(name: str) -> str | None:
    """The module ``name`` or its nearest enclosing module of the package."""
    while name and name not in MODULES:
        name = name.rsplit(".", 1)[0] if "." in name else ""
    return name or None


def _imports(module: str) -> set[tuple[str, int]]:
    """(imported mftire module, line) for every import statement of ``module``."""
    path = MODULES[module]
    is_pkg = path.name == "__init__.py"
    found: set[tuple[str, int]] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name == "mftire" or alias.name.startswith("mftire."):
                    found.add((_resolve(alias.name), node.lineno))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".") if is_pkg else module.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not (target == "mftire" or target.startswith("mftire.")):
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}"
                found.add((sub if sub in MODULES else _resolve(target), node.lineno))
    # importing a.b.c runs the sub-package __init__ files a.b on the way (the root is left out, see above)
    for target, line in list(found):
        parts = target.split(".")
        for i in range(2, len(parts)):
            found.add((".".join(parts[:i]), line))
    return {(t, line) for t, line in found if t and t != "mftire" and t != module
            and not module.startswith(t + ".")}  # a package's own __init__ is already running


def _graph() -> dict[str, set[tuple[str, str]]]:
    """module -> {(imported module, 'file:line' of the import)}."""
    return {m: {(t, f"{m}:{line}") for t, line in _imports(m)} for m in MODULES if m != "mftire"}


def _layer(module: str) -> str:
    parts = module.split(".")
    return ".".join(parts[:2])


def _cycles(graph: dict[str, set[tuple[str, str]]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan), each with its edges."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w, _ in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(f"{a} -> {b} ({where})" for a in comp for b, where in graph.get(a, ())
                                  if b in comp))
    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def test_graph_sees_lazy_and_relative_imports():
    g = _graph()
    # a function-level import (the CLI registers sub-commands lazily) is an edge
    assert any(t == "mftire.fitting.cli" for t, _ in g["mftire.cli"])
    assert any(t == "mftire.fitting" for t, _ in g["mftire.cli"])  # ... and runs mftire/fitting/__init__
    assert any(t == "mftire.iotools.loaders" for t, _ in g["mftire.compare.data"])
    assert len(MODULES) > 50


def test_no_module_imports_a_module_that_imports_it_back():
    assert _cycles(_graph()) == []


def test_no_cycle_between_layers():
    layers: dict[str, set[tuple[str, str]]] = {}
    for m, edges in _graph().items():
        node = layers.setdefault(_layer(m), set())
        node.update((_layer(t), where) for t, where in edges if _layer(t) != _layer(m))
    assert _cycles(layers) == []


def test_no_module_imports_names_from_the_root_package():
    bad = []
    for m, path in MODULES.items():
        if m == "mftire":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module == "mftire":
                bad += [f"{m}:{node.lineno} from mftire import {a.name}" for a in node.names
                        if f"mftire.{a.name}" not in MODULES]
            if isinstance(node, ast.Import) and any(a.name == "mftire" for a in node.names):
                bad.append(f"{m}:{node.lineno} import mftire")
    assert bad == []


# ------------------------------------------------------------------ the layer order (docs/architecture.md)
# Python layers only; checks of the C sources' #includes and the generated headers live in their own functions.

#: The layers of docs/architecture.md, bottom first: a module may import only from its own layer or below.
PY_LAYERS: tuple[tuple[str, ...], ...] = (
    ("mftire.errors", "mftire._lazy", "mftire.progress", "mftire.parallel", "mftire.data"),
    ("mftire.parameters",),
    ("mftire.iotools",),
    ("mftire.mf",),
    ("mftire.tyre", "mftire.input_checks", "mftire.curves", "mftire.extensions", "mftire.transient"),
    ("mftire.segmentation", "mftire.plotting", "mftire.report_html"),
    ("mftire.fe",),
    ("mftire.fmu",),
    ("mftire.compare",),
    ("mftire.fitting",),
    ("mftire.diagnosis",),
    ("mftire.demo", "mftire.cli", "mftire.cli_options"),
)
_CLI_RANK = len(PY_LAYERS) - 1


def py_layer_rank(module: str) -> int:
    """Rank of ``module`` in :data:`PY_LAYERS` (the ``cli`` module of every package is in the top layer)."""
    if module.endswith(".cli") or module == "mftire.cli":
        return _CLI_RANK
    for rank, names in enumerate(PY_LAYERS):
        if any(module == n or module.startswith(n + ".") for n in names):
            return rank
    raise AssertionError(f"{module} is in no layer of docs/architecture.md: add it to PY_LAYERS and the doc")


def test_every_module_has_a_layer_and_the_doc_names_every_layer():
    doc = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    for m in MODULES:
        if m != "mftire":
            py_layer_rank(m)
    for names in PY_LAYERS:
        for n in names:
            assert f"`{n}`" in doc, f"docs/architecture.md does not name {n}"


def test_imports_go_down_the_layers():
    climbs = []
    for m, edges in _graph().items():
        rank = py_layer_rank(m)
        for target, where in edges:
            if py_layer_rank(target) > rank:
                climbs.append(f"{where}: {m} (layer {rank + 1}) imports {target} (layer {py_layer_rank(target) + 1})")
    assert climbs == []


def test_no_argparse_below_the_cli_layer():
    found = []
    for m, path in MODULES.items():
        if m == "mftire" or py_layer_rank(m) == _CLI_RANK:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if any(n == "argparse" or n.startswith("argparse.") for n in names):
                found.append(f"{m}:{node.lineno}")
    assert found == []


#: The one crossing left, for the merge with the C-side work of issue 25: the latency path of Tyre.evaluate reads
#: the set of checked modes; mftire.mf.solver.valid_mode (its public check) replaces it, then this entry goes.
_PRIVATE_CROSSINGS_LEFT = {"mftire.tyre: _CHECKED_MODES from mftire.mf.solver"}


def test_no_private_name_imported_across_packages():
    crossing = []
    for m, path in MODULES.items():
        is_pkg = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom):
                continue
            if node.level:
                base = m.split(".") if is_pkg else m.split(".")[:-1]
                target = ".".join(base[: len(base) - (node.level - 1)] + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if not target.startswith("mftire") or _layer(target) == _layer(m):
                continue
            crossing += [f"{m}: {a.name} from {target}" for a in node.names
                         if a.name.startswith("_") and not a.name.startswith("__")]
    assert set(crossing) <= _PRIVATE_CROSSINGS_LEFT, sorted(set(crossing) - _PRIVATE_CROSSINGS_LEFT)


def test_module_names_say_what_they_hold():
    # no two modules of the package share a name (each package's cli and the public path mftire.extensions apart)
    by_name: dict[str, list[str]] = {}
    for m, path in MODULES.items():
        if path.name == "__init__.py":
            continue  # a package (mftire.data: the resources) is not a module file
        by_name.setdefault(m.rsplit(".", 1)[-1], []).append(m)
    shared = {n: ms for n, ms in by_name.items() if len(ms) > 1 and n not in ("cli", "extensions")}
    assert shared == {}


def test_package_module_maps_name_existing_modules():
    # the module tables in the docstrings of mftire.mf, mftire.fitting and mftire.compare name only modules
    # that exist, and every module of the package
    import re

    for pkg in ("mftire.mf", "mftire.fitting", "mftire.compare"):
        doc = ast.get_docstring(ast.parse(MODULES[pkg].read_text(encoding="utf-8"))) or ""
        listed = set(re.findall(r"^``(\w+)``\s", doc, flags=re.M))
        present = {m.rsplit(".", 1)[-1] for m in MODULES if m.startswith(pkg + ".") and m.count(".") == 2}
        assert listed == present, (pkg, sorted(listed ^ present))
