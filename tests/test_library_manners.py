"""Library manners: importing or running mftire leaves the caller's global state alone.

The caller's matplotlib backend, its warning filters and its working directory must be
the same after importing every mftire module and running the figure and report writers
(standard curves, comparison, fit report, diagnosis report, HTML report).  The check
runs in a fresh interpreter, so nothing imported by other tests hides a change.
A static check backs it: no ``matplotlib.use`` or pyplot import anywhere in the package,
and every ``warnings.simplefilter`` / ``filterwarnings`` sits inside a
``with warnings.catch_warnings()`` block.
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from conftest import REFERENCE_TYRES

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mftire"

_SCRIPT = textwrap.dedent(
    r"""
    import importlib, json, os, pkgutil, sys, warnings

    import matplotlib
    import numpy, pandas, scipy.optimize, matplotlib.figure  # third-party imports may set their own filters

    matplotlib.use("svg")  # the caller's choice: not Agg
    warnings.filterwarnings("error", message="caller sentinel")
    warnings.simplefilter("default", UserWarning)
    before = {"backend": matplotlib.get_backend(), "filters": [repr(f) for f in warnings.filters],
              "cwd": os.getcwd()}

    import mftire
    for m in pkgutil.walk_packages(mftire.__path__, "mftire."):
        importlib.import_module(m.name)
    imported = {"backend": matplotlib.get_backend(), "filters": [repr(f) for f in warnings.filters],
                "cwd": os.getcwd()}

    tir, out = sys.argv[1], sys.argv[2]
    import numpy as np
    from mftire.compare import compare, write_comparison
    from mftire.curves import standard_curves
    from mftire.diagnosis.diagnose import diagnose
    from mftire.diagnosis.report import write_report as write_diagnosis
    from mftire.fitting.fitter import fit_tir
    from mftire.fitting.fit_report import write_report as write_fit_report
    from mftire.fitting.synthetic import synthetic_sweeps
    from mftire.iotools.tir import read_tir
    from mftire.plotting import plot_standard_curves, subplots
    from mftire.report_html import HtmlReport
    from mftire.tyre import load

    tyre = load(tir)
    plot_standard_curves(standard_curves(tyre, n=21), os.path.join(out, "curves.png"), title="t")
    F0 = tyre["FNOMIN"]
    with warnings.catch_warnings():  # the test's own silence, scoped
        warnings.simplefilter("ignore")
        data = synthetic_sweeps(read_tir(tir), [0.7 * F0, 1.2 * F0], [0.0], n_kappa=15, n_alpha=15, n_combined=5,
                                noise=0.002, seed=3, channels=("Fx", "Fy"))  # two channels: fewer figures
    data["source"] = "syn"
    write_comparison(compare([tir], data, n_grid=21), os.path.join(out, "compare"))
    fit = fit_tir(data, tir, stages="1", progress=False)
    write_fit_report(fit, os.path.join(out, "fit"))
    d = data.copy()
    d["time"] = np.arange(len(d)) * 0.1
    write_diagnosis(diagnose(d, tyre, n_perm=9, progress=False), os.path.join(out, "diag"))
    fig, ax = subplots()
    ax.plot([0, 1], [0, 1])
    HtmlReport("t").add_figure(fig).write(os.path.join(out, "r.html"), os.path.join(out, "r.json"))

    after = {"backend": matplotlib.get_backend(), "filters": [repr(f) for f in warnings.filters],
             "cwd": os.getcwd()}
    print(json.dumps({"before": before, "imported": imported, "after": after,
                      "pyplot": "matplotlib.pyplot" in sys.modules,
                      "files": sorted(os.listdir(out)) + sorted(os.listdir(os.path.join(out, "fit")))}))
    """
)


def test_import_and_run_leave_backend_filters_and_cwd_alone(tmp_path):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("MPLBACKEND", None)
    run = subprocess.run([sys.executable, "-c", _SCRIPT, str(REFERENCE_TYRES["MF61"]), str(tmp_path)],
                         capture_output=True, text=True, env=env, cwd=tmp_path, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    res = json.loads(run.stdout.strip().splitlines()[-1])
    before = res["before"]
    assert before["backend"] == "svg"
    assert res["imported"] == before
    assert res["after"] == before
    assert not res["pyplot"]  # pyplot (and its figure registry) never loaded by the library
    files = res["files"]
    assert {"curves.png", "compare", "fit", "diag", "r.html"} <= set(files)
    assert any(f.endswith(".png") for f in files if f not in ("curves.png",))  # fit report figures written
    assert (tmp_path / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _py_files() -> list[Path]:
    return sorted(PACKAGE.rglob("*.py"))


def _is_call(node: ast.AST, names: set[str]) -> bool:
    if not isinstance(node, ast.Call):
        return False
    f = node.func
    return (isinstance(f, ast.Attribute) and f.attr in names) or (isinstance(f, ast.Name) and f.id in names)


def test_no_backend_switch_and_no_pyplot_in_the_package():
    bad = []
    for path in _py_files():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import) and any(a.name == "matplotlib.pyplot" for a in node.names):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno} imports pyplot")
            if isinstance(node, ast.ImportFrom) and (node.module == "matplotlib.pyplot" or (
                    node.module == "matplotlib" and any(a.name == "pyplot" for a in node.names))):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno} imports pyplot")
            if _is_call(node, {"use", "switch_backend"}) and "matplotlib" in ast.unparse(node.func):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno} {ast.unparse(node)}")
    assert bad == []


def _inside_catch_warnings(stack: list[ast.AST]) -> bool:
    return any(isinstance(n, ast.With) and any(_is_call(i.context_expr, {"catch_warnings"}) for i in n.items)
               for n in stack)


def test_warning_filters_only_inside_catch_warnings():
    bad = []

    def visit(node: ast.AST, stack: list[ast.AST], path: Path) -> None:
        if _is_call(node, {"simplefilter", "filterwarnings", "resetwarnings"}) and not _inside_catch_warnings(stack):
            bad.append(f"{path.relative_to(ROOT)}:{node.lineno} {ast.unparse(node)}")
        for child in ast.iter_child_nodes(node):
            visit(child, stack + [node], path)

    for path in _py_files():
        visit(ast.parse(path.read_text(encoding="utf-8")), [], path)
    assert bad == []


def test_cli_main_restores_signal_handlers_and_the_output_scope(tmp_path, capsys):
    """``mftire.cli.main`` turns SIGTERM into an interrupt and holds writes to the command's outputs only
    while the command runs (issue 24); afterwards the caller's handlers and free writes are back."""
    import signal

    from mftire.cli import main
    from mftire.iotools import output
    from mftire.iotools.atomic import write_text_atomic

    def mine(signum, frame):  # the caller's own handler
        pass

    old = signal.signal(signal.SIGTERM, mine)
    try:
        before = (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT), output._SCOPE.get())
        points = tmp_path / "p.csv"
        points.write_text("Fz,kappa,alpha,gamma\n4000,0,0.05,0\n")
        assert main(["evaluate", str(REFERENCE_TYRES["MF61"]), "--input", str(points), "--output",
                     str(tmp_path / "o.csv")]) == 0
        assert main(["info", str(tmp_path / "missing.tir")]) == 2
        assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT), output._SCOPE.get()) == before
        assert before[0] is mine and before[2] is None
        write_text_atomic(tmp_path / "free.txt", "a library write after a command is not held")
    finally:
        signal.signal(signal.SIGTERM, old)
    capsys.readouterr()
