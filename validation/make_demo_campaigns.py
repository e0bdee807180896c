"""Regenerate the simulated demonstration campaigns in validation/data/.

Each campaign is a measured-like test programme simulated with the FE surrogate
(:mod:`mftire.fe.programmes`), with rig artefacts (noise, Fz wander, offsets, drift),
and the MF 6.1 model fitted to it with ``mftire fit``.  Run from the repository root:

    python validation/make_demo_campaigns.py [NAME ...]
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from mftire.fe.programmes import PROGRAMMES, programme
from mftire.fitting.fitter import fit_tir
from mftire.iotools.atomic import atomic_path
from mftire.iotools.tir import write_tir

OUT = Path(__file__).resolve().parent / "data"


def make(name: str) -> None:
    pr = programme(name)
    fit = fit_tir(pr.data[pr.fit_rows.to_numpy()], pr.template, progress=False, fixed=pr.fixed)
    folder = OUT / name
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / "sweeps.csv") as tmp:
        pr.data.to_csv(tmp, index=False, float_format="%.10g")
    write_tir(fit.parameters, folder / "fitted.tir")
    print(f"{name}: {len(pr.data)} rows -> {folder}")


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    for name in sys.argv[1:] or PROGRAMMES:
        make(name)
