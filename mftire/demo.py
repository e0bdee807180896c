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
7. A third source, raw rig data (:func:`rig_stage`): the shipped SIMULATED TTC-style run
   file (``mftire/data/simulated_ttc_run.dat.gz``, 100 Hz, SAE axes, grip depending on
   the tread temperature) imported, fitted, diagnosed, and the error before and after on
   a held-out load.
8. The thermal tyre (:func:`thermal_stage`): the rig stage's MF 6.1 fit made thermal with
   ``fit-thermal`` on the first part of the shipped SIMULATED continuous thermal run
   (``mftire/data/simulated_thermal_run.dat.gz``), its held-out stint replayed, against the model
   fed the measured temperature and an isothermal fit.
"""

from __future__ import annotations

import os
import sys
import time
import warnings
from dataclasses import dataclass
from typing import Any

import pandas as pd

from mftire.batch import write_files
from mftire.iotools.atomic import atomic_path, staged_folder
from mftire.iotools.tir import write_tir
from mftire.parallel import Executor, FilesTask
from mftire.progress import Progress

#: Files and folders the demo writes into its output folder.
OUTPUT_NAMES = ("fe_sweeps.csv", "measured_sweeps.csv", "fitted.tir", "extended.tir", "tyre.fmu", "report.html",
                "report.json", "headline.png", "rig_sweeps.csv", "rig_fitted.tir", "rig_run.png", "thermal.tir",
                "thermal_replay.csv", "thermal_stint.png")


def run_demo(output: str | os.PathLike = "demo_out", quick: bool = False, progress: bool | None = None,
             executor: Executor | None = None) -> dict:
    """Run the demo; returns a summary dict (also in ``output/report.json``).

    ``executor`` runs the FE campaign chunks, the rig stage, the diagnosis, the bootstrap refits and
    the comparison figures (default: in this process, one step after the other; see
    :mod:`mftire.parallel`).  With workers, the independent stages overlap: the rig stage starts
    after the FE campaign, the diagnosis and the bootstrap refits as soon as the fit is done; the
    results do not depend on it.
    Warnings of the steps are silenced, and BLAS held to one thread, inside the run only (global filters
    and thread counts are restored).
    """
    from threadpoolctl import threadpool_limits

    # one BLAS thread in this process and the local workers it starts (forked inside): the steps make
    # many small SVDs, and idle BLAS threads spinning for work would take the cores from the workers
    with warnings.catch_warnings(), threadpool_limits(1, user_api="blas"):
        warnings.simplefilter("ignore")
        # every output is written into a staging folder and moved into ``output`` at the end: a run that
        # fails (a lost cluster, Ctrl-C) writes nothing there
        with (executor or Executor()).session() as ex, staged_folder(output) as stage:
            summary, closing = _run_demo(stage, quick, progress, ex)
    if progress is not False:  # the results on stdout (progress lines go to stderr), once the files are in place
        out = os.fspath(output)
        print(closing, flush=True)
        print(f"done: {os.path.join(out, 'report.html')}\n      {os.path.join(out, 'report.json')}", flush=True)
    return summary


def _rig_task(quick: bool, folder: str) -> tuple[RigStage, ThermalStage]:
    """:func:`rig_stage`, then :func:`thermal_stage` on its fitted ``.tir``, as a task for the executor
    (warnings silenced in the worker too); they write into a scratch ``folder`` of the worker, whose files
    :class:`~mftire.parallel.FilesTask` returns to the client."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rig = rig_stage(folder, quick)
        # scipy's BLAS, loaded in a worker after the run's limit, would start a thread per core for the thermal
        # fit's many small SVDs (3 x its CPU time on a busy 2-core machine): held to one here, now that it is loaded
        from threadpoolctl import threadpool_limits

        with threadpool_limits(1, user_api="blas"):
            return rig, thermal_stage(folder, os.path.join(folder, "rig_fitted.tir"))


def _diagnose_task(args: tuple) -> Any:
    """:func:`mftire.diagnosis.diagnose.diagnose` of the measured campaign as a task for the executor."""
    from mftire.diagnosis.diagnose import diagnose

    data, tyre, n_perm = args
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(data, tyre, progress=False, n_perm=n_perm)


def _run_demo(output: str | os.PathLike, quick: bool, progress: bool | None, executor: Executor) -> tuple[dict, str]:
    from mftire.compare.comparison import compare
    from mftire.diagnosis.report import write_report
    from mftire.fe.config import load_tyre
    from mftire.fe.programmes import programme
    from mftire.fe.slip_sweeps import campaign
    from mftire.fe.template import mf_template
    from mftire.fitting.bands import coverage_table, start_bootstrap_bands
    from mftire.fitting.fitter import fit_tir
    from mftire.report_html import HtmlReport
    from mftire.tyre import Tyre

    out = os.fspath(output)
    os.makedirs(out, exist_ok=True)
    reporter = Progress("mftire demo", progress, total=9)
    step = reporter.step

    step("FE-surrogate campaign of the default tyre" + (" (quick grid)" if quick else ""))
    fe_tyre = load_tyre(None)
    fe, free = campaign(fe_tyre, quick=quick, progress=False, executor=executor)
    # the rig stage needs nothing of the others: with workers it runs from now on, alongside them
    # (after the FE campaign, which keeps every worker busy)
    rig_pending = executor.start_map(FilesTask(_rig_task), [quick], labels=["the rig stage"])
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
    # with workers, the diagnosis goes to the first free one and the bootstrap refits (they need only the
    # fit) queue behind it: as many busy processes as workers, the diagnosis (which the rest waits for) first
    diag_pending = executor.start_map(_diagnose_task, [(meas, fitted, 49 if quick else 99)])

    step("diagnosis of the measured residual")
    diag = diag_pending.result()[0]
    diag_doc = write_report(diag, os.path.join(out, "diagnosis"))
    extended = diag.extended if diag.significant else None
    if extended is not None:
        extended.name = "MF 6.1 + " + diag.effect.name
        write_tir(extended.parameters, os.path.join(out, "extended.tir"))
    # the bands are made without the held-out condition (fit warm-started from the full fit), so that the
    # held-out points test them honestly; the bootstrap refits run while the FMU is written
    heldout = None
    held_rows = pd.Series(False, index=both.index)
    if diag.holdout is not None and diag.train is not None and len(diag.train) == len(meas):
        heldout = (diag.holdout["column"], list(diag.holdout["values"]), "measured")
        # the diagnosis keeps the measured rows in order (its table is the campaign with sweep columns added)
        held_rows = pd.Series(False, index=both.index)
        held_rows.iloc[len(fe):] = ~diag.train
    band_fit = fit_tir(both[~held_rows.to_numpy()], fit.parameters, weights="fe=1,measured=4", progress=False) \
        if held_rows.any() else fit
    bands_pending = start_bootstrap_bands(None, template, n=4 if quick else 12, fit=band_fit, stages="1,2,3", seed=0,
                                          calibrate=5, executor=executor, progress=False)  # fmt: skip

    step("FMU of the " + ("extended" if extended is not None else "fitted") + " model")
    fmu_info: dict = {}
    try:
        from mftire.fmu.export import export_fmu

        fmu_path = os.path.join(out, "tyre.fmu")
        export_fmu(extended or fitted, fmu_path)
        fmu_info = {"path": "tyre.fmu", "bytes": os.path.getsize(fmu_path)}
    except Exception as exc:  # noqa: BLE001 - the report says why there is no FMU
        fmu_info = {"error": str(exc)}

    step("bootstrap bands over sweeps, calibrated on out-of-fold sweeps")
    bands = bands_pending.result()
    coverage = None
    if held_rows.any():
        coverage = coverage_table(bands, meas[~diag.train].assign(source="measured"))

    step("curve comparison: MF against FE against measured")
    models = {"MF fit": fitted}
    if extended is not None:
        models["MF + " + diag.effect.name] = extended
    comp = compare(models, both, bands=bands, heldout=heldout)
    fig_dir = os.path.join(out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    plots = comp.plots(fig_dir, executor=executor)

    step("third source: the simulated raw rig run imported, fitted, diagnosed" + (" (quick)" if quick else "")
         + "; the thermal tyre fitted and replayed")  # fmt: skip
    (rig, thermal), rig_files = rig_pending.result()[0]
    write_files(out, rig_files)  # computed on a worker, written here

    step("HTML report")
    rep = HtmlReport("mftire demo: MF 6.1 from FE and measured sweeps, closed loop",
                     "All data are simulated: FE surrogate, a measured-like campaign and a raw rig run "
                     "(see README)")  # fmt: skip
    rep.add_heading("Summary")
    summary = {
        "fe_points": len(fe), "measured_points": len(meas),
        "fitted_coefficients": len(dict.fromkeys(fit.identified)), "not_identified": len(fit.not_identified),
        **_diagnosis_numbers(diag),
    }  # fmt: skip
    summary["band_level"] = bands.level
    if coverage is not None and len(coverage):
        last = coverage.iloc[-1]
        summary["heldout_inside_prediction_band"] = float(last["inside_prediction"])
        summary["heldout_band_sweeps"] = int(last["sweeps"])
        for r in coverage.itertuples(index=False):
            if r.channel != "all":
                summary[f"heldout_{r.channel}_inside_prediction_band"] = float(r.inside_prediction)
                summary[f"heldout_{r.channel}_inside_prediction_band_se"] = float(r.se_prediction)
    if bands.calibration is not None:
        for ch, per in bands.calibration.cv_coverage.items():
            if "measured" in per:
                summary[f"cv_{ch}_inside_prediction_band"] = per["measured"]
    summary["rig"] = {k: rig.summary[k] for k in ("cause", "effect", "heldout_load_N")}
    summary["rig"].update({k: v for k, v in rig.summary.items() if k.startswith("heldout_") and "rms" in k})
    summary["thermal"] = {k: thermal.summary[k] for k in THERMAL_SUMMARY_KEYS if k in thermal.summary}
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
    rep.add_text(f"Bootstrap over sweeps, {len(bands.replicates)} replicates, level {bands.level:g}, of a fit without "
                 "the held-out condition: confidence band of the mean curve; prediction band (for a new measured "
                 "point) calibrated on out-of-fold sweeps: split conformal over the effective number of sweeps, "
                 "heteroscedastic scale per channel, source and slip class with a local factor of load, speed, "
                 "pressure and camber. The held-out coverage counts few sweeps: its s.e. is over the sweeps. "
                 + " ".join(bands.notes))  # fmt: skip
    if coverage is not None:
        rep.add_table(coverage, caption="held-out measured points inside the bands", key="band_coverage")
    if bands.calibration is not None:
        rep.add_table(pd.DataFrame([{"channel": ch, "source": src, "inside_prediction": v, "nominal": bands.level}
                                    for ch, per in bands.calibration.cv_coverage.items() for src, v in per.items()]),
                      caption="cross-validated coverage: each fold of sweeps against the band calibrated on the "
                              "others, by a model fitted without it", key="band_cv_coverage")  # fmt: skip
    _rig_section(rep, rig, out)
    _thermal_section(rep, thermal, out)
    rep.add_heading("Outputs")
    rep.add_numbers("files", {"fitted_tir": "fitted.tir", "extended_tir": "extended.tir" if extended else None,
                              "fmu": fmu_info, "diagnosis": "diagnosis/diagnosis.md",
                              "rig_sweeps": "rig_sweeps.csv", "rig_fitted_tir": "rig_fitted.tir",
                              "rig_diagnosis": "rig_diagnosis/diagnosis.md", "thermal_tir": "thermal.tir",
                              "thermal_replay": "thermal_replay.csv"})  # fmt: skip
    rep.write(os.path.join(out, "report.html"), os.path.join(out, "report.json"))
    _headline(comp, diag, os.path.join(out, "headline.png"))
    return summary, headline_text(summary, diag, reporter.elapsed())


def headline_text(summary: dict, diag, run_time_s: float) -> str:
    """The demo's closing lines: held-out errors before and after, the cause, the band coverage, the run time."""
    L = [f"done in {run_time_s:.1f} s"]
    if diag.holdout is not None and diag.errors:
        col, vals = diag.holdout["column"], diag.holdout["values"]
        where = ", ".join(f"{v * 3.6:.0f} km/h" if col == "Vx" else f"{v:g}" for v in vals)
        L.append(f"  held-out {col} = {where}: RMS error in % of peak, MF fit -> MF + {summary.get('effect')}")
        for e in diag.errors:
            L.append(f"    {e.channel}: {e.rms_pct_before:.2f} % -> {e.rms_pct_after:.2f} %")
    L.append(f"  cause: {summary.get('cause')} (effect {summary.get('effect')})")
    lvl = 100 * summary.get("band_level", 0.95)
    held = [f"{k.split('_')[1]} {100 * v:.1f} %" + (f" (s.e. {100 * se:.1f})" if (se := summary.get(k + "_se"))
                                                      is not None and se == se else "")
            for k, v in summary.items()
            if k.startswith("heldout_") and k.endswith("_inside_prediction_band") and k.count("_") == 4]
    cv = [f"{k.split('_')[1]} {100 * v:.1f} %" for k, v in summary.items() if k.startswith("cv_")]
    if held:
        sw = summary.get("heldout_band_sweeps")
        L.append(f"  {lvl:g} % prediction band, held-out points inside: " + ", ".join(held)
                 + (f" ({sw} sweeps; s.e. over the sweeps)" if sw else ""))
    if cv:
        L.append("    cross-validated over sweeps (measured): " + ", ".join(cv))
    rig = summary.get("rig", {})
    if rig:
        L.append(f"  rig run: cause {rig.get('cause')}, held-out load {rig.get('heldout_load_N', 0):.0f} N: "
                 + ", ".join(f"{ch} {rig[f'heldout_{ch}_rms_pct_before']:.2f} -> "
                             f"{rig[f'heldout_{ch}_rms_pct_after']:.2f} %" for ch in ("Fx", "Fy")
                             if f"heldout_{ch}_rms_pct_before" in rig))
    th = summary.get("thermal", {})
    if th:
        L.append(f"  thermal stint (held out, {th['heldout_rows']} rows): surface temperature "
                 f"{th['surface_rms_K']:.2f} K RMS; RMS error replay / fed the measured temperature / isothermal fit: "
                 + ", ".join(f"{ch} {th[f'thermal_{ch}_rms_N']:.0f} / {th[f'measured_temperature_{ch}_rms_N']:.0f} / "
                             f"{th[f'isothermal_{ch}_rms_N']:.0f} N" for ch in ("Fx", "Fy")
                             if f"thermal_{ch}_rms_N" in th))
    return "\n".join(L)


def _diagnosis_numbers(diag) -> dict:
    """Cause, effect and the held-out RMS (% of peak) before and after, and its cut, per channel."""
    out = {"diagnosis": diag.summary(), "cause": diag.ranking[0].variable if diag.significant else None,
           "effect": diag.effect.name if diag.effect is not None and diag.significant else None}  # fmt: skip
    for e in diag.errors:
        out[f"heldout_{e.channel}_rms_pct_before"] = e.rms_pct_before
        out[f"heldout_{e.channel}_rms_pct_after"] = e.rms_pct_after
        out[f"heldout_{e.channel}_cut"] = 1.0 - e.rms_after / e.rms_before if e.rms_before else None
    return out


#: The demo's rig run: 10 points per sweep, and every ``RIG_PAIR_STEP``-th pair of sweeps (one
#: up, one down) of the shipped file, (full, quick): 100 and 68 of its 400 sweeps.  The
#: whole file takes 3-4 times as long to fit and diagnose (validation/make_rig_file.py --chain OUT 1).
RIG_POINTS_PER_SWEEP = 10
RIG_PAIR_STEP = (4, 6)
#: The load held out of the rig fit and of the effect fit [x FNOMIN].
RIG_HOLDOUT_LOAD = 0.7


@dataclass
class RigStage:
    """What :func:`rig_stage` produced."""

    summary: dict
    import_report: Any  #: :class:`mftire.segmentation.rig_segments.RigReport` of the whole file
    fit: Any  #: :class:`mftire.fitting.fitter.FitResult` of the rig sweeps
    diagnosis: Any  #: :class:`mftire.diagnosis.diagnose.DiagnosisResult`
    diagnosis_doc: dict


def rig_stage(output: str | os.PathLike, quick: bool = False, pair_step: int | None = None) -> RigStage:
    """The demo's third data source: raw rig data, SIMULATED.

    1. ``mftire import`` of the shipped run file (:func:`mftire.data.rig_run`: TTC-style
       layout, SAE axes, 100 Hz, 54,400 rows): SAE -> ISO, segmentation, 10 points per
       sweep; the demo keeps every ``RIG_PAIR_STEP``-th pair of sweeps (``pair_step``: another
       step, 1 for the whole file), written to ``rig_sweeps.csv``, so that the stage stays short;
    2. MF 6.1 fit (template: the package's default ``.tir``, a 255/55 R20 parameter set
       other than the one that made the data) to every load but ``RIG_HOLDOUT_LOAD`` x
       FNOMIN, written to ``rig_fitted.tir``;
    3. diagnosis of the residual with that load held out (the tread temperatures ``TSTI``,
       ``TSTC``, ``TSTO`` are candidates like any other column), in ``rig_diagnosis/``;
    4. held-out RMS error before (MF fit) and after (MF + the diagnosed effect).
    """
    import numpy as np

    from mftire.data import default_tir, rig_run
    from mftire.diagnosis.diagnose import diagnose
    from mftire.diagnosis.report import write_report
    from mftire.fitting.fitter import fit_tir
    from mftire.iotools.rig import read_ttc, write_sweeps
    from mftire.iotools.tir import read_tir
    from mftire.plotting import subplots
    from mftire.segmentation.rig_segments import segment
    from mftire.tyre import Tyre

    out = os.fspath(output)
    t0 = time.perf_counter()
    path = rig_run()
    raw = read_ttc(path)
    table, imp = segment(raw, points_per_sweep=RIG_POINTS_PER_SWEEP, name=os.path.basename(path), keep_dropped=False)
    table = table.drop(columns=["fit_row", "drop_reason"])  # sweep rows only: the demo's tables as before
    step = pair_step or RIG_PAIR_STEP[1 if quick else 0]
    sweeps = table[(table["sweep_id"] // 2) % step == 0].reset_index(drop=True).assign(source="rig")
    write_sweeps(sweeps, os.path.join(out, "rig_sweeps.csv"))
    t_import = time.perf_counter() - t0

    template = read_tir(default_tir())
    fnomin = float(template["FNOMIN"])
    held = np.isclose(sweeps["Fz_set"], RIG_HOLDOUT_LOAD * fnomin, rtol=0.05)
    fit = fit_tir(sweeps[~held], template, progress=False)
    write_tir(fit.parameters, os.path.join(out, "rig_fitted.tir"))
    fitted = Tyre(fit.parameters, name="MF 6.1 fit to the rig run")
    level = float(sweeps.loc[held, "Fz_set"].iloc[0])
    diag = diagnose(sweeps, fitted, ("Fz", [level]), progress=False, n_perm=49 if quick else 99)
    doc = write_report(diag, os.path.join(out, "rig_diagnosis"))

    summary: dict = {
        "data": "SIMULATED raw rig run (not measured): mftire/data/simulated_ttc_run.dat.gz, made by "
                "validation/make_rig_file.py",
        "raw_rows": imp.n_rows, "duration_s": imp.duration_s, "sample_rate_hz": imp.sample_rate_hz,
        "axes": f"{imp.convention.upper()} -> ISO W", "sweeps_imported": imp.n_sweeps, "points_imported": imp.n_points,
        "rows_dropped": int(sum(imp.dropped.values())), "sweeps_used": int(sweeps["sweep_id"].nunique()),
        "points_used": len(sweeps), "pair_step": step, "template": "default.tir (mftire.data.default_tir)",
        "heldout_load_N": level, **_diagnosis_numbers(diag),
    }  # fmt: skip
    summary["import_s"] = t_import
    summary["stage_s"] = time.perf_counter() - t0

    # the raw run: load, slip and tread temperature against time, the sweeps used marked
    r = raw
    fig, axs = subplots(3, 1, figsize=(8.0, 6.0), sharex=True, constrained_layout=True)
    axs[0].plot(r["ET"], r["Fz"] / 1e3, lw=0.5)
    axs[0].set_ylabel("Fz [kN]")
    axs[1].plot(r["ET"], np.degrees(r["alpha"]), lw=0.3, label="α [deg]")
    axs[1].plot(r["ET"], 100 * r["kappa"], lw=0.3, label="κ [%]")
    axs[1].set_ylabel("slip: α [deg], κ [%]")
    axs[1].legend(loc="upper right", fontsize=8)
    for c in ("TSTI", "TSTC", "TSTO"):
        axs[2].plot(r["ET"], r[c], lw=0.5, label=c)
    axs[2].set_ylabel("tread surface [°C]")
    axs[2].set_xlabel("ET [s]")
    axs[2].legend(loc="upper right", fontsize=8)
    spans = sweeps.assign(held=held).groupby("sweep_id").agg(lo=("ET", "min"), hi=("ET", "max"), held=("held", "first"))
    for a in axs:
        for lo, hi, h in spans.itertuples(index=False):
            a.axvspan(lo, hi, color="#f4b6b6" if h else "0.85", lw=0)
        a.grid(alpha=0.3)
    axs[0].set_title("SIMULATED raw rig run (ISO W axes); shaded: sweeps used, red: the held-out load", fontsize=10)
    with atomic_path(os.path.join(out, "rig_run.png")) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    return RigStage(summary, imp, fit, diag, doc)


def _rig_section(rep, rig: RigStage, out: str) -> None:
    """The report section of the rig stage."""
    import numpy as np

    s, imp, diag = rig.summary, rig.import_report, rig.diagnosis
    rep.add_heading("Third source: raw rig time series (SIMULATED)")
    rep.add_text("Simulated, not measured: a flat-track run file in the TTC-style layout (tab-separated, metric "
                 "units, SAE axes, 100 Hz) made by validation/make_rig_file.py from an MF 6.1 tyre whose grip "
                 "depends on the tread temperature (first-order thermal model driven by friction power), with "
                 "sensor noise, load wander and FZ crosstalk into FY. mftire import converts it to ISO W axes, "
                 "drops warm-up, ramps and dwells and cuts it into sweeps; MF 6.1 is fitted with one load held "
                 "out, and the diagnosis looks for the cause of the residual among every column.")  # fmt: skip
    rep.add_numbers("rig", s)
    rep.add_figure(os.path.join(out, "rig_run.png"), caption="raw run: load, slip and tread temperatures")
    rep.add_table(pd.DataFrame([{"reason": k, "rows": v, "share": v / max(imp.n_rows, 1)}
                                for k, v in sorted(imp.dropped.items(), key=lambda kv: -kv[1])]),
                  caption=f"import: {imp.n_rows} rows, {imp.rows_kept} kept in {imp.n_sweeps} sweeps; rows dropped",
                  key="rig_import_dropped")  # fmt: skip
    rep.add_table(pd.DataFrame([{"stage": st.number, "name": st.name, "channel": st.channel, "points": st.n_points,
                                 "status": st.status, "rms": st.rms} for st in rig.fit.stages]),
                  caption="staged fit of the rig sweeps", key="rig_fit_stages")  # fmt: skip
    rep.add_text(diag.summary())
    rep.add_table(pd.DataFrame(rig.diagnosis_doc["ranking"]).head(10), caption="candidate ranking (first 10)",
                  key="rig_diagnosis_ranking")  # fmt: skip
    if diag.errors:
        err = pd.DataFrame([vars(e) for e in diag.errors])
        err["cut"] = 1.0 - err["rms_after"] / err["rms_before"].replace(0.0, np.nan)
        rep.add_table(err, caption=f"held-out load {s['heldout_load_N']:.0f} N: before (MF fit) and after "
                                   "(MF + the diagnosed effect)", key="rig_heldout")  # fmt: skip
    folder = os.path.join(out, "rig_diagnosis")
    for png in ("curves_before_after.png", *sorted(f for f in os.listdir(folder) if f.startswith("profile_"))):
        p = os.path.join(folder, png)
        if os.path.exists(p):
            rep.add_figure(p, caption="rig: " + png[:-4].replace("_", " "))


#: The shipped thermal run's stint starts at this time [s] (``validation/make_thermal_runs.split_time``): the
#: thermal fit uses the warm-up and load steps before it, the stint is held out.
THERMAL_SPLIT_S = 470.0
#: The thermal stage's numbers in the demo's summary (and its closing lines).
THERMAL_SUMMARY_KEYS = ("heldout_rows", "surface_rms_K", "pressure_rms_kPa", "thermal_Fx_rms_N", "thermal_Fy_rms_N",
                        "measured_temperature_Fx_rms_N", "measured_temperature_Fy_rms_N", "isothermal_Fx_rms_N",
                        "isothermal_Fy_rms_N", "Fx_ratio_to_measured_temperature", "Fy_ratio_to_measured_temperature",
                        "Fx_cut_vs_isothermal", "Fy_cut_vs_isothermal")  # fmt: skip


@dataclass
class ThermalStage:
    """What :func:`thermal_stage` produced."""

    summary: dict
    table: pd.DataFrame  #: RMS error of Fx, Fy on the held-out stint per model
    parameters: pd.DataFrame  #: the fitted thermal parameters with their standard errors
    laws: pd.DataFrame  #: each temperature law, its node and the held-out errors of the nodes tried


def thermal_stage(output: str | os.PathLike, tir: str | os.PathLike) -> ThermalStage:
    """The demo's thermal tyre (issue 22), on SIMULATED data.

    The shipped continuous thermal rig run (:func:`mftire.data.thermal_run`: TTC layout, 10 Hz, 680 s, the
    same 255/55 R20 parameter set as the rig stage's run, a layered tread model and a sealed tyre) is read
    as ``mftire fit-thermal`` reads it; the thermal tyre is fitted to ``tir`` (the rig stage's MF 6.1 fit) on
    ``ET <= THERMAL_SPLIT_S`` (warm-up and load steps) and the stint after it replayed from kinematics and
    conditions only (:func:`mftire.thermal.heldout.heldout_check`, as ``mftire replay``), against the same laws
    fed the measured temperature and an isothermal fit.  Writes ``thermal.tir``, ``thermal_replay.csv`` (the
    replay, as ``mftire replay`` writes it) and ``thermal_stint.png``.
    """
    import numpy as np

    from mftire.data import thermal_run
    from mftire.iotools.rig import read_ttc
    from mftire.plotting import subplots
    from mftire.thermal.heldout import heldout_check
    from mftire.thermal.thermal_fit import UNITS, measured_surface

    out = os.fspath(output)
    t0, c0 = time.perf_counter(), time.process_time()
    path = thermal_run()
    df = read_ttc(path)
    chk = heldout_check(tir, df, THERMAL_SPLIT_S, name=os.path.basename(path))
    write_tir(chk.fit.tir, os.path.join(out, "thermal.tir"))
    with atomic_path(os.path.join(out, "thermal_replay.csv")) as tmp:
        chk.replay.table.to_csv(tmp, index=False)
    th = chk.fit.thermal
    summary: dict = {
        "data": "SIMULATED continuous thermal rig run (not measured): mftire/data/simulated_thermal_run.dat.gz, "
                "made by validation/make_thermal_runs.py",
        "tir": "rig_fitted.tir (the rig stage's MF 6.1 fit)", "raw_rows": len(df),
        **chk.numbers(), "fit_surface_rms_K": th.rms_surface, "fit_pressure_rms_kPa": th.rms_pressure / 1e3,
        "laws": "; ".join(f"EXT{c.index} {c.description}: node {c.node}" for c in chk.fit.laws),
        "replay_iterations": chk.replay.iterations,
    }  # fmt: skip
    params = pd.DataFrame([{"parameter": f"TH_{k.upper()}", "value": getattr(th.params, k), "sigma": v,
                            "unit": UNITS[k]} for k, v in th.sigma.items()])  # fmt: skip
    laws = pd.DataFrame([{"law": f"EXT{c.index} {c.description}", "node": c.node,
                          **{f"heldout_{k}": v for k, v in c.heldout.items()}} for c in chk.fit.laws])  # fmt: skip

    # the run, the split and the held-out stint: surface temperature, Fy error of the three models, pressure
    t = df["ET"].to_numpy(float)
    held = t > THERMAL_SPLIT_S
    rep, iso = chk.replay.table, chk.isothermal.table
    fig, axs = subplots(3, 1, figsize=(8.0, 7.5), sharex=True, constrained_layout=True)
    axs[0].plot(t, measured_surface(df), ".", ms=1.5, color="0.5", label="measured (mean of TSTI/TSTC/TSTO)")
    axs[0].plot(t, rep["T_surface"], lw=1.0, color="C3", label="surface node (replay)")
    axs[0].plot(t, rep["T_bulk"], lw=0.8, ls="--", color="C1", label="bulk node")
    axs[0].set_ylabel("temperature [°C]")
    axs[0].legend(fontsize=7, loc="upper left")
    y = df["Fy"].to_numpy(float)
    for lab, f, c in (("isothermal fit", iso["Fy_model"], "0.3"), ("fed the measured temperature",
                      chk.measured["Fy"], "C0"), ("thermal replay (no temperature input)", rep["Fy_model"], "C3")):
        axs[1].plot(t[held], (np.asarray(f, float) - y)[held], lw=0.6, color=c,
                    label=f"{lab}: RMS {np.sqrt(np.mean(((np.asarray(f, float) - y)[held]) ** 2)):.0f} N")
    axs[1].set_ylabel("Fy error [N]")
    axs[1].legend(fontsize=7, loc="lower left")
    if "P" in rep.columns:
        axs[2].plot(t, rep["P"] / 1e3, ".", ms=1.5, color="0.5", label="measured")
    axs[2].plot(t, rep["P_model"] / 1e3, lw=1.0, color="C3", label="gas law of the gas node (replay)")
    axs[2].set_ylabel("pressure [kPa]")
    axs[2].set_xlabel("ET [s]")
    axs[2].legend(fontsize=7, loc="upper left")
    for a in axs:
        a.axvspan(THERMAL_SPLIT_S, t[-1], color="0.92", lw=0)
        a.grid(alpha=0.3)
    axs[0].set_title(f"SIMULATED thermal rig run: fit on ET ≤ {THERMAL_SPLIT_S:g} s, the stint held out (shaded): "
                     f"surface {chk.surface_rms:.2f} K RMS", fontsize=10)  # fmt: skip
    with atomic_path(os.path.join(out, "thermal_stint.png")) as tmp:
        fig.savefig(tmp, format="png", dpi=100)
    summary["stage_s"] = time.perf_counter() - t0  # with the figure
    summary["stage_cpu_s"] = time.process_time() - c0  # this process's CPU time
    return ThermalStage(summary, chk.table(), params, laws)


def _thermal_section(rep, thermal: ThermalStage, out: str) -> None:
    """The report section of the thermal stage."""
    s = thermal.summary
    rep.add_heading("Thermal tyre: fitted on a continuous rig run, its held-out stint replayed (SIMULATED)")
    rep.add_text("Simulated, not measured: a continuous flat-track run of the same tyre (TTC layout, 10 Hz, SAE "
                 "axes) made by validation/make_thermal_runs.py from a richer thermal model than the one fitted "
                 "(four conduction layers through the tread, a carcass and the gas, a grip law with a threshold, "
                 "a sealed tyre). The rig stage's MF 6.1 fit is made thermal (three nodes, gas law, temperature "
                 f"laws; mftire fit-thermal) on ET <= {s['split_s']:g} s, and the stint after it is replayed from "
                 "kinematics and conditions only (mftire replay), against the same laws fed the measured "
                 "temperature and pressure, and an isothermal fit (LMUX, LMUY, LKX, LKY refitted at the cold "
                 "pressure). The force errors include the MF fit's own error.")  # fmt: skip
    rep.add_numbers("thermal", s)
    rep.add_table(thermal.table, caption=f"held-out stint ({s['heldout_rows']} rows): RMS error per model",
                  key="thermal_heldout")  # fmt: skip
    rep.add_table(thermal.parameters, caption="fitted thermal parameters, ± one standard error (a lower bound: "
                  "the residuals are correlated in time)", key="thermal_parameters")  # fmt: skip
    rep.add_table(thermal.laws, caption="temperature laws: the node each reads, by held-out error",
                  key="thermal_laws")  # fmt: skip
    rep.add_figure(os.path.join(out, "thermal_stint.png"), caption="thermal run: surface temperature, Fy error on "
                   "the held-out stint, pressure")  # fmt: skip


def _headline(comp, diag, path: str) -> None:
    """One figure: braking at the held-out speed, measured vs MF fit vs MF + effect."""
    from mftire.plotting import subplots

    if diag.data is None or diag.train is None or diag.extended is None:
        return
    import numpy as np
    held = diag.data[~diag.train]
    braking = held[np.abs(held["alpha"].to_numpy(float)) < 1e-9]
    from matplotlib.lines import Line2D

    fig, ax = subplots(figsize=(8.5, 4.8), constrained_layout=True)
    handles = []
    by = next(c for c in ("load_fraction", "Fz_set", "sweep_id") if c in braking.columns)
    for i, (_, g) in enumerate(braking.groupby(by)):  # one curve per load
        g = g.sort_values("kappa")
        c = f"C{i}"
        ax.plot(g["kappa"], g["Fx"], ".", color=c, ms=5)
        ax.plot(g["kappa"], g["Fx"] - g["residual_Fx"], "--", color=c)
        ax.plot(g["kappa"], g["Fx"] - g["residual_after_Fx"], "-", color=c)
        lf = f"{float(g['load_fraction'].iloc[0]):.2g} × LI, " if "load_fraction" in g else ""
        handles.append(Line2D([], [], color=c, lw=3, label=f"{lf}Fz ≈ {g['Fz'].mean():.0f} N"))
    handles += [Line2D([], [], color="k", marker=".", linestyle="none", label="measured (held out)"),
                Line2D([], [], color="k", linestyle="--", label="MF 6.1 fit"),
                Line2D([], [], color="k", linestyle="-", label=f"MF + {diag.effect.name}")]
    v = diag.holdout["values"][0]
    ax.set_title(f"held-out braking at {v * 3.6:.0f} km/h: measured, MF fit, MF with the diagnosed effect")
    ax.set_xlabel("κ [-]")
    ax.set_ylabel("Fx [N]")
    ax.grid(alpha=0.3)
    ax.legend(handles=handles, fontsize=8)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110)


def main(output: str = "demo_out", quick: bool = False) -> int:
    """Entry for ``python -m mftire.demo [OUTPUT]`` (all cores)."""
    run_demo(output, quick=quick, progress=True, executor=Executor(jobs=None))
    return 0


if __name__ == "__main__":
    sys.exit(main(*(sys.argv[1:2] or ["demo_out"])))

