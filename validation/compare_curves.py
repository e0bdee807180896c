"""Compare MF curves, FE-surrogate sweeps and measured sweeps with the ``mftire.compare`` API.

Runs on its own (no files needed):

1. the quick FE-surrogate campaign of the default tyre (``mftire fe campaign --quick``);
2. a measured-like data set: the shipped default ``.tir`` evaluated on a sweep design
   with 2 % noise (source ``rig``), split into fitting loads and held-out loads;
3. MF 6.1 fitted to the rig data with bootstrap bands (bootstrap over sweeps);
4. the comparison of the template and the fitted model against FE and rig data, with
   the bands drawn, plus the held-out coverage of the bands;
5. an HTML report (figures embedded) with a JSON sidecar.

    python validation/compare_curves.py [--output DIR] [--replicates N]
"""

from __future__ import annotations

import argparse
import os
import warnings

import numpy as np
import pandas as pd

from mftire.compare import compare, prepare_comparison_data, write_comparison
from mftire.data import default_tir
from mftire.fe.config import load_tyre
from mftire.fe.slip_sweeps import campaign
from mftire.fitting.bands import bootstrap_bands, coverage_table
from mftire.fitting.fitter import fit_tir
from mftire.fitting.synthetic import synthetic_sweeps
from mftire.iotools.tir import read_tir, write_tir
from mftire.parameters import with_defaults
from mftire.report_html import HtmlReport


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--output", default="compare_curves_out")
    ap.add_argument("--replicates", type=int, default=20)
    args = ap.parse_args()
    os.makedirs(args.output, exist_ok=True)
    warnings.simplefilter("ignore")

    fe, _ = campaign(load_tyre(None), quick=True, progress=False)
    fe = fe.rename(columns={"kind": "fe_kind"}).assign(source="fe", origin="fe")

    tmpl = read_tir(default_tir())
    F0 = with_defaults(tmpl)["FNOMIN"]
    rig = synthetic_sweeps(tmpl, [0.5 * F0, F0, 1.5 * F0], np.radians([0.0, 2.0]), n_kappa=25, n_alpha=25,
                           n_combined=13, noise=0.02, seed=1).assign(source="rig", origin="measured")
    held = synthetic_sweeps(tmpl, [0.75 * F0, 1.25 * F0], [0.0], n_kappa=25, n_alpha=25, n_combined=13,
                            noise=0.02, seed=2).assign(source="rig", origin="measured")

    fit = fit_tir(rig, tmpl, progress=True)
    fitted = os.path.join(args.output, "fitted.tir")
    write_tir(fit.parameters, fitted)
    bands = bootstrap_bands(rig, tmpl, n=args.replicates, fit=fit, progress=True)
    cov = coverage_table(bands, held)

    data = prepare_comparison_data(pd.concat([rig, fe], ignore_index=True))
    comp = compare({"template": default_tir(), "fitted": fitted}, data, bands=bands)
    paths = write_comparison(comp, args.output)
    print(comp.summary.to_string(index=False))
    print(cov.to_string(index=False))

    rep = HtmlReport("MF / FE / measurement comparison", subtitle="validation/compare_curves.py")
    rep.add_heading("Held-out coverage of the bootstrap bands")
    rep.add_text(" ".join(bands.notes))
    rep.add_table(cov, key="coverage")
    rep.add_heading("Error summary")
    rep.add_table(comp.summary, key="summary")
    rep.add_heading("Stiffness against load")
    rep.add_table(comp.stiffness, key="stiffness")
    rep.add_heading("Figures")
    for p in paths["plots"]:
        rep.add_figure(p, caption=os.path.basename(p))
    html, js = rep.write(os.path.join(args.output, "report.html"))
    print(f"wrote {paths['markdown']}, {paths['json']}, {html}, {js}")


if __name__ == "__main__":
    main()
