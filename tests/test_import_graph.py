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
import re
import shutil
import subprocess
from pathlib import Path

import pytest

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
# Python layers only; the C sources' #includes and the generated headers are checked at the end of this file.

#: The layers of docs/architecture.md, bottom first: a module may import only from its own layer or below.
PY_LAYERS: tuple[tuple[str, ...], ...] = (
    ("mftire.errors", "mftire._lazy", "mftire.progress", "mftire.parallel", "mftire.dask_plugins", "mftire.data"),
    ("mftire.parameters",),
    ("mftire.iotools",),
    ("mftire.mf",),
    ("mftire.tyre", "mftire.input_checks", "mftire.curves", "mftire.extensions", "mftire.transient",
     "mftire.thermal", "mftire.batch", "mftire.streaming"),
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


#: No crossing left (the latency path of Tyre.evaluate reads the public mftire.mf.solver.CHECKED_MODES / valid_mode).
_PRIVATE_CROSSINGS_LEFT: set[str] = set()


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


# ------------------------------------------------------------------ the C files: #includes (docs/architecture.md)

C_MODEL = PACKAGE / "mf" / "c"
C_FMU = PACKAGE / "fmu" / "c"
#: The headers an FMU's export generates next to the sources (its variable table, the FMI standard's headers).
FMU_GENERATED = {"mf_model_gen.h", "mt_model_gen.h", "mf_params.h", "mf_ext_gen.h", "mt_config_gen.h"} | {
    f"fmi{v}{h}" for v in (2, 3) for h in ("Functions.h", "FunctionTypes.h", "TypesPlatform.h", "PlatformTypes.h")
}


def _c_includes(text: str) -> list[tuple[int, str, bool]]:
    """(line, file, after code) for every ``#include "file"`` of a C text: ``after code`` when a line of code
    (not a comment, a blank or a preprocessor line) stands before it."""
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    out, code = [], False
    for i, line in enumerate(text.splitlines(), 1):
        line = line.split("//")[0].strip()
        m = re.match(r'#\s*include\s+"([^"]+)"', line)
        if m:
            out.append((i, m.group(1), code))
        elif line and not line.startswith("#") and not line.endswith("\\"):
            code = True
    return out


def _generated_c_headers() -> dict[str, str]:
    """The generated headers as their generators write them (the model's committed ones and an FMU's)."""
    from mftire.fmu import variables as vt
    from mftire.fmu.transient_export import transient_model_header, transient_variable_table
    from mftire.mf import cheaders
    from mftire.mf.extensions import parse_section
    from mftire.parameters import with_defaults

    flat = with_defaults({"FITTYP": 61.0})
    ext = parse_section({"EXT1_TARGET": "LMUX", "EXT1_FORM": "quadratic", "EXT1_VARIABLE": "dfz", "EXT1_C1": 0.1,
                         "EXT1_C2": 0.01})  # fmt: skip
    table = vt.variable_table(flat, vt.DEFAULT_USE_MODE, ext)
    out = {"mf_spec_gen.h": cheaders.spec_header(), **{f"kernel/{k}": v for k, v in cheaders.kernel_headers().items()}}
    out["fmu mf_ext_gen.h"] = cheaders.extension_header(ext)
    out["fmu mf_params.h"] = vt.params_header(table, ext)
    out["fmu mf_model_gen.h"] = vt.model_header(table, "id", 2)
    out["fmu mt_model_gen.h"] = transient_model_header(transient_variable_table(flat), "id")
    out["fmu mt_config_gen.h"] = cheaders.transient_config_header(False)
    out["fmu thermal mt_config_gen.h"] = cheaders.transient_config_header(True, (0, 1), 273.15)
    return out


def test_c_includes_go_down_the_layers():
    """The C model (mftire/mf/c) includes only its own files and the generated headers its build provides;
    the FMI wrappers (mftire/fmu/c) include the model's headers, their own and the FMU's generated ones --
    nothing in mf/c reaches up into fmu/c.  The generated headers include only the model's interfaces: the
    extension code (mf_ext_gen.h) only mf_ext.h, the value-reference tables only the model they describe."""
    # the transient model's configuration (thermal block on or off) is generated by the model layer
    # (mftire.mf.cheaders.transient_config_header) and written by the transient FMU export, as mf_ext_gen.h is
    mf_files = {p.name for p in C_MODEL.glob("*.[ch]")} | {p.name for p in (C_MODEL / "kernel").glob("*.h")} | {
        "mt_config_gen.h"}
    fmu_files = {p.name for p in C_FMU.glob("*.[ch]")}
    bad = [(p.name, name) for p in C_MODEL.glob("*.[ch]") for _, name, _ in _c_includes(p.read_text("utf-8"))
           if name not in mf_files or name in fmu_files]
    bad += [(p.name, name) for p in C_FMU.glob("*.[ch]") for _, name, _ in _c_includes(p.read_text("utf-8"))
            if name not in mf_files | fmu_files | FMU_GENERATED]
    assert bad == []
    allowed = {"mf_ext_gen.h": {"mf_ext.h"}, "mf_model_gen.h": {"mf_eval.h"}, "mt_model_gen.h": {"mf_transient.h"},
               "mf_params.h": set(), "mf_spec_gen.h": set(), "mt_config_gen.h": set()}  # fmt: skip
    for key, text in _generated_c_headers().items():
        name = key.split()[-1].split("/")[-1]
        assert {inc for _, inc, _ in _c_includes(text)} <= allowed[name], key


def test_c_headers_are_included_at_the_top():
    """Every ``#include`` of a header stands before the first line of code of its file, hand-written or
    generated: no file reaches into another's middle (a ``.c`` file included into a translation unit, as
    mf_kernel.c includes mf_eval.c, is composition, not an interface, and may follow its settings)."""
    texts = {p.name: p.read_text("utf-8") for d in (C_MODEL, C_FMU) for p in d.glob("*.[ch]")}
    texts.update(_generated_c_headers())
    late = [f"{name}:{line} includes {inc} after code" for name, text in texts.items()
            for line, inc, after in _c_includes(text) if after and inc.endswith(".h")]
    assert late == []
    assert any(inc == "mf_ext_gen.h" for _, inc, _ in _c_includes(texts["mf_eval.c"]))  # the check sees it


@pytest.mark.skipif(not any(shutil.which(c) for c in ("cc", "gcc", "clang")), reason="no C compiler")
def test_generated_extension_code_needs_only_its_interface(tmp_path):
    """mf_ext_gen.h (every builtin variable and form: the array kernel's) compiles on its own with mf_ext.h:
    it uses nothing of mf_eval.c that the interface does not declare."""
    cc = next(c for c in ("cc", "gcc", "clang") if shutil.which(c))
    src = tmp_path / "ext_only.c"
    src.write_text('#define MF_FN static\n#include "mf_ext_gen.h"\n'
                   "double probe(const MFParams *p, const Cond *c) { return mf_ext_var(7, p, c, 0)"
                   " * mf_ext_form(5, 1.0, 0.5, 0.0, 1.0, 0, 2); }\n", encoding="utf-8")  # fmt: skip
    argv = [cc, "-std=c99", "-Werror=implicit-function-declaration", "-fsyntax-only", f"-I{C_MODEL / 'kernel'}",
            f"-I{C_MODEL}", str(src)]
    res = subprocess.run(argv, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]


# ------------------------------------------------------------------ walks: the calls of the main entry points
#
# A walk follows every Python call made inside mftire by one entry point (sys.setprofile) and records the module
# of the callee and of its nearest mftire caller.  A climb is a call from a module to one in a higher layer of
# docs/architecture.md (a callback handed down and called back up, or a lower layer reaching up by name).
# Module bodies run by an import are not calls (the import graph above checks those).
# ``python -m pytest tests/test_import_graph.py -k walks -s`` prints the table of docs/architecture.md.


def walk(fn, *args, **kwargs) -> tuple[list[str], list[str]]:
    """(the modules entered, in order of first entry; the climbs as "caller -> callee.function") of one call."""
    import sys

    rooms: dict[str, None] = {}
    climbs: dict[str, None] = {}

    def module_of(frame) -> str | None:
        name = frame.f_globals.get("__name__", "")
        return name if name == "mftire" or name.startswith("mftire.") else None

    def profile(frame, event, arg):
        if event != "call" or frame.f_code.co_name == "<module>":
            return
        callee = module_of(frame)
        if callee is None:
            return
        rooms.setdefault(callee)
        up = frame.f_back
        while up is not None and module_of(up) is None:
            up = up.f_back
        caller = module_of(up) if up is not None else None
        if caller and caller != callee and py_layer_rank(caller) < py_layer_rank(callee):
            climbs.setdefault(f"{caller} -> {callee}.{frame.f_code.co_name}")

    sys.setprofile(profile)
    try:
        fn(*args, **kwargs)
    finally:
        sys.setprofile(None)
    return list(rooms), list(climbs)


def _walks(tmp_path: Path) -> dict[str, tuple[list[str], list[str]]]:
    import warnings

    import numpy as np
    import pandas as pd

    from mftire.fitting import fit_tir
    from mftire.fmu.export import export_fmu
    from mftire.tyre import load

    tir = ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir"
    tyre = load(tir)
    kappa = np.linspace(-0.2, 0.2, 21)
    frames = []
    for fz in (3000.0, 4500.0, 6000.0):
        out = tyre.evaluate(fz, kappa, 0.0)
        frames.append(pd.DataFrame({"Fz": fz, "kappa": kappa, "alpha": 0.0, "gamma": 0.0, "Vx": 16.7,
                                    "P": tyre["NOMPRES"], "Fx": np.asarray(out["Fx"])}))  # fmt: skip
    data = pd.concat(frames, ignore_index=True)
    tyre.evaluate(4000.0, 0.05, 0.01)  # what the first call of a session loads (the kernel) is loaded
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            "Tyre.evaluate (arrays)": walk(tyre.evaluate, [3000.0, 5000.0], [0.05, -0.1], [0.01, 0.02]),
            "Tyre.evaluate (numpy)": walk(tyre.evaluate, [3000.0, 5000.0], [0.05, -0.1], [0.01, 0.02],
                                          backend="numpy"),
            "Tyre.evaluate (one point)": walk(tyre.evaluate, 4000.0, 0.05, 0.01),
            "fit_tir": walk(fit_tir, data, tir, stages="1", progress=False),
            "export_fmu": walk(export_fmu, tyre, tmp_path / "walk.fmu"),  # (transient=True: 0 climbs too, +4 s)
        }


@pytest.mark.skipif(not any(shutil.which(c) for c in ("cc", "gcc", "clang")), reason="no C compiler")
def test_walks_of_the_entry_points_go_down_the_layers(tmp_path):
    walks = _walks(tmp_path)
    print("\n| entry point | layers entered (top first) | modules | climbs |\n|---|---|---|---|")
    for name, (rooms, climbs) in walks.items():
        layers = sorted({py_layer_rank(m) + 1 for m in rooms}, reverse=True)
        print(f"| `{name}` | {', '.join(map(str, layers))} | {len(rooms)} | {len(climbs)} |")
    for name, (rooms, _) in walks.items():
        print(f"{name}: {' > '.join(rooms)}")
    assert {name: climbs for name, (_, climbs) in walks.items() if climbs} == {}
    assert all(len(rooms) >= 2 for rooms, _ in walks.values()) and len(walks["fit_tir"][0]) > 10  # it sees calls
