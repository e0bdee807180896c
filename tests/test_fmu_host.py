"""The fmpy host of the FMU (mftire.fmu.host): every instance logs through its own callback.

fmpy's logger proxy keeps one process-wide pointer to the last Python logger registered;
a host that registered it per instance sent every message to the newest instance and,
once that one was freed, through a dangling pointer.  The host now gives each instance
a plain callback of its own (the FMUs pass their messages pre-formatted).
"""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from conftest import needs_c_compiler

ROOT = Path(__file__).resolve().parents[1]
TIR = ROOT / "tests" / "data" / "tir" / "MagicFormula61_Parameters.tir"

SCRIPT = textwrap.dedent(
    """
    import gc, json, math, sys
    from fmpy import extract
    from mftire.fmu.host import FMUTyre

    unzipdir = extract(sys.argv[1])
    kept = []
    for rnd in range(3):
        made = [FMUTyre(unzipdir, "ME" if i % 2 else "CS", instance_name=f"t{rnd}_{i}") for i in range(12)]
        for i, tyre in enumerate(made):
            if i % 5 == 2:
                kept.append(tyre)
            else:
                tyre.close()
        del made, tyre
        gc.collect()  # the freed hosts' callbacks are gone now
    out = []
    for j, tyre in enumerate(kept):
        tyre.messages.clear()
        tyre.evaluate(Fz=math.nan, kappa=0.0, alpha=0.0)  # a warning through the FMI logger
        try:
            tyre.fmu.setDebugLogging(True, [f"no-such-{j}%d"])  # an error with a '%' in its text
        except Exception:
            pass
        out.append([list(m) for m in tyre.messages])
    for tyre in kept:
        tyre.close()
    print(json.dumps(out))
    """
)


@needs_c_compiler
def test_many_instances_created_and_freed_then_logging(tmp_path):
    from mftire.fmu.export import export_fmu

    fmu = export_fmu(TIR, tmp_path / "tyre.fmu")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]))
    res = subprocess.run([sys.executable, "-c", SCRIPT, str(fmu)], capture_output=True, text=True, timeout=300, env=env)
    assert res.returncode == 0, res.stderr[-2000:]  # no crash (a dangling logger would segfault here)
    per_instance = json.loads(res.stdout.splitlines()[-1])
    assert len(per_instance) == 6
    for j, messages in enumerate(per_instance):
        # each kept instance got exactly its own two messages, formatted, in its own list
        assert len(messages) == 2, messages
        (s1, c1, m1), (s2, c2, m2) = messages
        assert (s1, c1) == (1, "logStatusWarning") and "NaN value(s) in input 'Fz'" in m1
        assert (s2, c2) == (3, "logStatusError") and m2 == f"unknown log category 'no-such-{j}%d'"
