"""Run ``mftire diagnose`` on the campaigns with unanticipated effects and tabulate the outcome.

Run from the repository root::

    python validation/diagnose_unanticipated.py [full|reduced] [CASE ...]

For each case of ``validation/data/unanticipated[_reduced]/`` (made by
``validation/make_unanticipated_campaigns.py``) it diagnoses ``sweeps.csv`` against the plain fit
``fitted.tir`` with the held-out condition of ``expected.json`` and prints one Markdown table row:
the expected and the found cause, the law (scaling factors and form), and the held-out Fx+Fy RMS
before and after, with the cut, the best cut the generating model reaches and the ceiling cut of a refit
with the generating law (``oracle``).
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from mftire import load
from mftire.diagnosis.diagnose import diagnose

ROOT = Path(__file__).resolve().parent / "data"


def main(argv: list[str]) -> int:
    kind = argv[0] if argv and argv[0] in ("full", "reduced") else "reduced"
    folder = ROOT / ("unanticipated" if kind == "full" else "unanticipated_reduced")
    cases = [a for a in argv if a not in ("full", "reduced")] or sorted(p.name for p in folder.iterdir()
                                                                         if (p / "expected.json").exists())
    print(f"| case ({kind}) | expected | found first | law | held-out Fx+Fy RMS before -> after [N] | cut | "
          "best cut | ceiling cut | time |")
    print("|---|---|---|---|---:|---:|---:|---:|---:|")
    for case in cases:
        d = folder / case
        exp = json.loads((d / "expected.json").read_text())
        h = exp["holdout"]
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = diagnose(pd.read_csv(d / "sweeps.csv"), load(d / "fitted.tir"),
                           holdout=(h["column"], h["values"]), progress=False)  # fmt: skip
        dt = time.perf_counter() - t0
        best = exp.get("oracle", {}).get("best_cut")
        ceiling = exp.get("oracle", {}).get("ceiling_cut")
        ceil = "-" if ceiling is None else f"{100 * ceiling:.0f} %"
        want = exp["variable"] if exp["effect"] else "no effect"
        if not res.significant:
            print(f"| {case} | {want} | no finding | - | - | - | {best if best is None else f'{100 * best:.0f} %'} "
                  f"| {ceil} | {dt:.0f} s |")
            continue
        ssb = sum(c.rms_before**2 * c.n for c in res.errors if c.channel in ("Fx", "Fy"))
        ssa = sum(c.rms_after**2 * c.n for c in res.errors if c.channel in ("Fx", "Fy"))
        n = sum(c.n for c in res.errors if c.channel in ("Fx", "Fy"))
        before, after = np.sqrt(ssb / n), np.sqrt(ssa / n)
        e = res.effect
        print(f"| {case} | {want} | {res.ranking[0].variable} | {'·'.join(e.targets) or e.name} × {e.name} in "
              f"{e.variable} | {before:.1f} -> {after:.1f} | {100 * (1 - after / before):.0f} % | "
              f"{'-' if best is None else f'{100 * best:.0f} %'} | {ceil} | {dt:.0f} s |")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
