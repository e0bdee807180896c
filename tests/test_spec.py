"""The one spec (mftire/mf/spec.py) drives the Python evaluator, the C model, the kernel and the FMU.

* the committed ``mftire/mf/c/mf_spec_gen.h`` is the generator's output;
* the tables are consistent with the C structs and the Python conditions;
* a dummy output added to the spec alone appears in the numpy evaluator, the compiled kernel
  (built from a copy of the C sources with the regenerated header) and an exported FMU,
  with the value of the channel it copies.
"""

from __future__ import annotations

import dataclasses
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from mftire.mf import cheaders, spec
from mftire.mf.inputs import Conditions

ROOT = Path(__file__).resolve().parents[1]
C_DIR = ROOT / "mftire" / "mf" / "c"


def have_c_compiler() -> bool:
    return any(shutil.which(c) for c in ("cc", "gcc", "clang"))


def test_generated_header_is_current():
    """Regenerate with ``python -m mftire.mf.cheaders``."""
    assert (C_DIR / "mf_spec_gen.h").read_text(encoding="utf-8") == cheaders.spec_header()


def _c_struct_fields(header: str, name: str) -> set[str]:
    body = re.search(r"typedef struct \{(.*?)\}\s*" + name + ";", header, re.S).group(1)
    body = re.sub(r"/\*.*?\*/", "", body, flags=re.S)
    return set(re.findall(r"\b([A-Za-z_]\w*)\s*(?:[,;\[])", body)) - {"double"}


def test_tables_match_the_c_structs_and_the_conditions():
    eval_h = (C_DIR / "mf_eval.h").read_text(encoding="utf-8")
    mf_outputs = _c_struct_fields(eval_h, "MFOutputs")
    assert {"Fx", "Kxk", "a2", "b2", "Cz"} <= mf_outputs
    conditions = {f.name for f in dataclasses.fields(Conditions)}
    groups = {g.name for g in spec.GROUPS}
    assert [g.bit for g in spec.GROUPS] == [1 << k for k in range(len(spec.GROUPS))]
    for o in spec.OUTPUTS:
        assert o.group is None or o.group in groups, o
        assert o.field is None or o.field in mf_outputs, o
        assert o.cond is None or o.cond in conditions, o
        assert o.field or o.cond, o
        assert o.fmu is None or o.field, o  # the FMU reads MFOutputs
    names = [o.name for o in spec.OUTPUTS]
    assert len(set(names)) == len(names) == 30
    fmu = [o.fmu for o in spec.OUTPUTS if o.fmu]
    assert len(set(fmu)) == len(fmu)
    from mftire.fmu.variables import UNITS

    assert all(o.unit == "-" or o.unit in UNITS for o in spec.OUTPUTS)
    for w in spec.WARNINGS:
        assert (w.limit is None) or ("{limit}" in w.text and "{value}" in w.text), w
        assert (w.input is None) == ("{input}" not in w.text), w
        assert w.input is None or w.input in spec.KERNEL_INPUTS, w
    assert len(spec.WARNINGS) < 64  # bits of an unsigned long mask


def test_python_reads_the_spec():
    from mftire.fmu.transient_export import OUTPUT_GROUPS
    from mftire.fmu.variables import OUTPUTS as FMU_OUTPUTS
    from mftire.mf import kernel, solver
    from mftire.mf.family import MODEL_CODES

    assert solver.OUTPUT_NAMES == kernel.OUTPUTS == tuple(o.name for o in spec.OUTPUTS)
    assert solver.OUTPUT_UNITS["Mz"] == "N.m" and solver.OUTPUT_UNITS["Kya"] == "N/rad"
    assert solver.CHANNEL_NEEDS["Mz"] == ("Mz",) and solver.CHANNEL_NEEDS["sigmax"] == ("Fx", "Fy")
    assert [r[0] for r in FMU_OUTPUTS][:3] == ["Fx", "Fy", "Fz_out"]
    assert OUTPUT_GROUPS["t"] == "MZ" and "Re" not in OUTPUT_GROUPS
    assert MODEL_CODES == {"MF 5.2": 6.0, "MF 6.1": 61.0, "MF 6.2": 62.0, "PAC2002": 2002.0, "MF-Tyre 5.0": 2002.0}


_DUMMY = r"""
import json, shutil, sys, warnings
from pathlib import Path

import mftire.mf.spec as spec

# the one change: a new output row (the loaded radius under another name, published by the FMU)
spec.OUTPUTS = spec.OUTPUTS + (spec.Output("dummyRl", "m", "RAD", "Rl", None, "dummyRl", "test output"),)

from mftire.fmu import build  # noqa: E402
from mftire.mf import _kernel_build, cheaders, kernel  # noqa: E402

# unoptimised builds: the test is about where the output reaches, not speed (IEEE results are the same at -O0:
# no fast-math, -ffp-contract=off kept), and -O3 / -O2 take most of its time
_kernel_build.CFLAGS = tuple("-O0" if f.startswith("-O") else f for f in _kernel_build.CFLAGS)
build.CFLAGS = tuple("-O0" if f.startswith("-O") else f for f in build.CFLAGS)
repo, tmp = Path(sys.argv[1]), Path(sys.argv[2])
shutil.copytree(repo / "mftire" / "mf" / "c", tmp / "mftire" / "mf" / "c")
(tmp / "mftire" / "mf" / "c" / "mf_spec_gen.h").write_text(cheaders.spec_header(), encoding="utf-8")
lib = _kernel_build.compile_library(tmp, tmp / _kernel_build.LIBRARY)
kernel._ROOT = tmp  # the copy the library was built from
assert kernel.load(lib) is not None, kernel.status()

from mftire import load  # noqa: E402
from mftire.fmu.export import export_fmu  # noqa: E402
from mftire.fmu.host import FMUTyre  # noqa: E402

warnings.simplefilter("ignore")
tyre = load(repo / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir")
args = ([3000.0, 4500.0, 6000.0], [0.02, -0.05, 0.1], [0.01, 0.03, -0.05])
res = {}
for backend in ("numpy", "kernel"):
    out = tyre.evaluate(*args, backend=backend)
    res[backend] = [list(map(float, out["dummyRl"])), list(map(float, out["Rl"]))]
point = tyre.evaluate(4500.0, -0.05, 0.03)  # the latency path of the kernel
res["point"] = [float(point["dummyRl"]), float(point["Rl"])]
export_fmu(tyre, tmp / "t.fmu")
with FMUTyre(tmp / "t.fmu") as fmu:
    got = fmu.evaluate(4500.0, -0.05, 0.03)
    res["fmu"] = [got["dummyRl"], got["Rl"]]
print(json.dumps(res))
"""


@pytest.mark.skipif(not have_c_compiler(), reason="no C compiler")
def test_a_dummy_output_added_to_the_spec_alone_reaches_python_kernel_and_fmu(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    run = subprocess.run([sys.executable, "-c", textwrap.dedent(_DUMMY), str(ROOT), str(tmp_path)],
                         capture_output=True, text=True, env=env, timeout=600)  # fmt: skip
    assert run.returncode == 0, run.stderr[-3000:]
    res = json.loads(run.stdout.strip().splitlines()[-1])
    for backend in ("numpy", "kernel"):
        dummy, rl = res[backend]
        assert dummy == rl and 0.2 < rl[0] < 0.4, res
    assert res["point"][0] == res["point"][1]
    assert res["fmu"][0] == res["fmu"][1] and abs(res["fmu"][0] - res["point"][1]) < 1e-9
