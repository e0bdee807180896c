"""``mftire demo``: the whole loop on the shipped default data, in one run.

1. FE-surrogate campaign of the default tyre (the thesis's programme).
2. A measured-like campaign of the "real" tyre: simulated with a friction law that
   depends on the local sliding speed and with rig artefacts (noise, Fz wander,
   offsets, drift) — the effect nobody declared.
3. MF 6.1 fitted to FE and measured data together, measured sweeps weighted higher.
4. Diagnosis of the measured residual: ranked causes, the missing effect added,
   refitted, and the error before and after on a held-out speed.
5. The fitted and extended ``.tir`` files and an FMU of the extended model.
6. Curve comparison (MF against FE against measured) with bootstrap bands, and one
   self-contained HTML report; every number of the report is also in a JSON file.
"""

from __future__ import annotations

import os
import sys
import time
import warnings

import pandas as pd

from mftire.iotools.atomic import atomic_path
from mftire.iotools.tir import write_tir
from mftire.parallel import Executor


class _Steps:
    def __init__(self, total: int, enabled: bool) -> None:
        self.total, self.enabled, self.i, self.t0 = total, enabled, 0, time.perf_counter()

    def __call__(self, msg: str) -> None:
        self.i += 1
        if self.enabled:
            print(f"[{self.i}/{self.total} {time.perf_counter() - self.t0:5.1f} s] {msg}", flush=True)


#: Files and folders the demo writes into its output folder.
OUTPUT_NAMES = ("fe_sweeps.csv", "measured_sweeps.csv", "fitted.tir", "extended.tir", "tyre.fmu", "report.html",
                "report.json", "headline.png")


def run_demo(output: str | os.PathLike = "demo_out", quick: bool = False, progress: bool = True,
             executor: Executor | None = None) -> dict:
    """Run the demo; returns a summary dict (also in ``output/report.json``).

    ``executor`` runs the FE campaign chunks and the bootstrap refits (default: in this process;
    see :mod:`mftire.parallel`); the results do not depend on it.
    Warnings of the steps are silenced inside the run only (global filters are restored).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _run_demo(output, quick, progress, executor)


def _run_demo(output: str | os.PathLike, quick: bool, progress: bool, executor: Executor | None) -> dict:
    from mftire.compare.core import compare
    from mftire.diagnosis.diagnose import diagnose
    from mftire.diagnosis.report import write_report
    from mftire.fe.config import load_tyre
    from mftire.fe.programmes import programme
    from mftire.fe.sweeps import campaign
    from mftire.fe.template import mf_template
    from mftire.fitting.bands import bootstrap_bands, coverage_table
    from mftire.fitting.core import fit_tir
    from mftire.report_html import HtmlReport
    from mftire.tyre import Tyre

    out = os.fspath(output)
    os.makedirs(out, exist_ok=True)
    step = _Steps(8, progress)

    step("FE-surrogate campaign of the default tyre" + (" (quick grid)" if quick else ""))
    fe_tyre = load_tyre(None)
    fe, free = campaign(fe_tyre, quick=quick, progress=False, executor=executor)
    fe = fe.assign(source="fe")
    with atomic_path(os.path.join(out, "fe_sweeps.csv")) as tmp:
        fe.to_csv(tmp, index=False)

    step("measured-like campaign (sliding-speed friction, rig artefacts)")
    meas = programme("slip_speed", seed=1, scale=0.5 if quick else 1.0, executor=executor).data
    meas = meas.assign(source="measured")
    with atomic_path(os.path.join(out, "measured_sweeps.csv")) as tmp:
        meas.to_csv(tmp, index=False)

    step("MF 6.1 fit to FE and measured data together (weights fe=1, measured=4)")
    template = mf_template(fe_tyre)
    both = pd.concat([fe, meas], ignore_index=True, sort=False)
    fit = fit_tir(both, template, weights="fe=1,measured=4", progress=False)
    write_tir(fit.parameters, os.path.join(out, "fitted.tir"))
    fitted = Tyre(fit.parameters, name="MF 6.1 fit")

    step("diagnosis of the measured residual")
    diag = diagnose(meas, fitted, progress=False, n_perm=49 if quick else 99)
    diag_doc = write_report(diag, os.path.join(out, "diagnosis"))
    extended = diag.extended if diag.significant else None
    if extended is not None:
        extended.name = "MF 6.1 + " + diag.effect.name
        write_tir(extended.parameters, os.path.join(out, "extended.tir"))

    step("FMU of the " + ("extended" if extended is not None else "fitted") + " model")
    fmu_info: dict = {}
    try:
        from mftire.fmu.export import export_fmu

        fmu_path = os.path.join(out, "tyre.fmu")
        export_fmu(extended or fitted, fmu_path)
        fmu_info = {"path": "tyre.fmu", "bytes": os.path.getsize(fmu_path)}
    except Exception as exc:  # noqa: BLE001 - the report says why there is no FMU
        fmu_info = {"error": str(exc)}

    step("bootstrap bands over sweeps")
    heldout_rows = diag.data is not None and diag.train is not None
    bands = bootstrap_bands(None, template, n=4 if quick else 12, fit=fit, stages="1,2,3", seed=0,
                            executor=executor)
    coverage = None
    if heldout_rows:
        held = diag.data[~diag.train]
        coverage = coverage_table(bands, held.assign(source="measured"))

    step("curve comparison: MF against FE against measured")
    models = {"MF fit": fitted}
    if extended is not None:
        models["MF + " + diag.effect.name] = extended
    comp = compare(models, both, bands=bands)
    fig_dir = os.path.join(out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    plots = comp.plots(fig_dir)

    step("HTML report")
    rep = HtmlReport("mftire demo: MF 6.1 from FE and measured sweeps, closed loop",
                     "All data are simulated: FE surrogate and a measured-like campaign (see README)")  # fmt: skip
    rep.add_heading("Summary")
    summary = {
        "fe_points": len(fe), "measured_points": len(meas),
        "fitted_coefficients": len(dict.fromkeys(fit.identified)), "not_identified": len(fit.not_identified),
        "diagnosis": diag.summary(),
        "cause": diag.ranking[0].variable if diag.significant else None,
        "effect": diag.effect.name if diag.effect is not None and diag.significant else None,
    }  # fmt: skip
    for e in diag.errors:
        summary[f"heldout_{e.channel}_rms_pct_before"] = e.rms_pct_before
        summary[f"heldout_{e.channel}_rms_pct_after"] = e.rms_pct_after
    if coverage is not None and len(coverage):
        last = coverage.iloc[-1]
        summary["band_level"] = bands.level
        summary["heldout_inside_prediction_band"] = float(last["inside_prediction"])
    rep.add_numbers("summary", summary)
    rep.add_heading("Fit")
    rep.add_table(pd.DataFrame([{"stage": s.number, "name": s.name, "channel": s.channel, "points": s.n_points,
                                 "status": s.status, "rms_start": s.rms_start, "rms": s.rms} for s in fit.stages]),
                  caption="staged fit", key="fit_stages")  # fmt: skip
    rep.add_table(fit.free_rolling, caption="free-rolling Fx: measured against fitted", key="free_rolling_fit")
    rep.add_heading("Curve comparison")
    for name, df in comp.tables().items():
        rep.add_table(df, caption=name.replace("_", " "), key=f"compare_{name}", max_rows=40)
    for path in plots:
        rep.add_figure(path, caption=os.path.splitext(os.path.basename(path))[0].replace("_", " "))
    rep.add_heading("Diagnosis of the measured residual")
    rep.add_text(diag.summary())
    rep.add_table(pd.DataFrame(diag_doc["ranking"]), caption="candidate ranking", key="diagnosis_ranking")
    if diag.errors:
        rep.add_table(pd.DataFrame([vars(e) for e in diag.errors]),
                      caption=f"held-out {diag.holdout['column']} = {diag.holdout['values']}: before and after",
                      key="diagnosis_heldout")  # fmt: skip
    profiles = sorted(f for f in os.listdir(os.path.join(out, "diagnosis")) if f.startswith("profile_"))
    for png in ("ranking.png", "curves_before_after.png", *profiles):
        p = os.path.join(out, "diagnosis", png)
        if os.path.exists(p):
            caption = png[:-4].replace("_", " ")
            if png.startswith("profile_"):
                caption = (f"scaling factor {png[8:-4]} refitted per sweep against the cause, with the fitted law "
                           "(mftire.diagnosis.profile)")  # fmt: skip
            rep.add_figure(p, caption=caption)
    rep.add_heading("Uncertainty")
    rep.add_text(f"Bootstrap over sweeps, {len(bands.replicates)} replicates, level {bands.level:g}: "
                 "prediction bands (replicate spread plus residual scatter).")  # fmt: skip
    if coverage is not None:
        rep.add_table(coverage, caption="held-out measured points inside the bands", key="band_coverage")
    rep.add_heading("Outputs")
    rep.add_numbers("files", {"fitted_tir": "fitted.tir", "extended_tir": "extended.tir" if extended else None,
                              "fmu": fmu_info, "diagnosis": "diagnosis/diagnosis.md"})  # fmt: skip
    html, js = rep.write(os.path.join(out, "report.html"), os.path.join(out, "report.json"))
    _headline(comp, diag, os.path.join(out, "headline.png"))
    if progress:
        print(f"done: {html}\n      {js}", flush=True)
    return summary


def _headline(comp, diag, path: str) -> None:
    """One figure: braking at the held-out speed, measured vs MF fit vs MF + effect."""
    from mftire.plotting import subplots

    if diag.data is None or diag.train is None or diag.extended is None:
        return
    import numpy as np
    held = diag.data[~diag.train]
    braking = held[np.abs(held["alpha"].to_numpy(float)) < 1e-9]
    fig, ax = subplots(figsize=(7.5, 4.5), constrained_layout=True)
    for i, (lf, g) in enumerate(braking.groupby("load_fraction")):
        g = g.sort_values("kappa")
        c = f"C{i}"
        ax.plot(g["kappa"], g["Fx"], ".", color=c, ms=5, label=f"measured {lf:.1f} LI" if i == 0 else None)
        ax.plot(g["kappa"], g["Fx"] - g["residual_Fx"], "--", color=c, label="MF 6.1 fit" if i == 0 else None)
        ax.plot(g["kappa"], g["Fx"] - g["residual_after_Fx"], "-", color=c,
                label=f"MF + {diag.effect.name}" if i == 0 else None)  # fmt: skip
    v = diag.holdout["values"][0]
    ax.set_title(f"held-out braking at {v * 3.6:.0f} km/h: measured, MF fit, MF with the diagnosed effect")
    ax.set_xlabel("κ [-]")
    ax.set_ylabel("Fx [N]")
    ax.grid(alpha=0.3)
    ax.legend()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)


def main(output: str = "demo_out", quick: bool = False) -> int:
    """Entry for ``python -m mftire.demo [OUTPUT]`` (all cores)."""
    run_demo(output, quick=quick, progress=True, executor=Executor(jobs=None))
    return 0


if __name__ == "__main__":
    sys.exit(main(*(sys.argv[1:2] or ["demo_out"])))

