"""Start-up: the command line and ``import mftire`` load neither pandas, scipy nor matplotlib
(issue 15; the time itself is measured by benchmarks/bench_cli.py)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("pandas", "scipy", "matplotlib")


def _loaded_after(code: str) -> list[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))"
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_cli_import_and_parser_are_light():
    assert _loaded_after("import mftire.cli\nmftire.cli.build_parser()") == []


def test_info_is_light():
    tir = ROOT / "tests/data/tir/mfeval/MagicFormula61_Paramerters.tir"
    code = f"import contextlib, io, mftire.cli\nwith contextlib.redirect_stdout(io.StringIO()):\n" \
           f"    assert mftire.cli.main(['info', {str(tir)!r}]) == 0"
    assert _loaded_after(code) == []


def test_public_api_loads_on_use():
    assert _loaded_after("import mftire") == []
    tir = ROOT / "tests/data/tir/mfeval/MagicFormula61_Paramerters.tir"
    code = ("import mftire\nfrom mftire.fitting import fit_tir\nfrom mftire.compare import compare\n"
            f"t = mftire.load({str(tir)!r})\n"
            "assert abs(float(t.evaluate(Fz=4000.0, kappa=-0.1, alpha=0.0)['Fx'][()]) ) > 100\n"
            "assert callable(fit_tir) and callable(compare) and 'Tyre' in dir(mftire)")
    assert set(_loaded_after(code)) >= {"pandas", "scipy"}
