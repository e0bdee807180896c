"""diagnosis.md, diagnosis.json and figures of a :class:`DiagnosisResult`."""

from __future__ import annotations

import json
import os
from dataclasses import asdict

import numpy as np
from matplotlib import colormaps

from mftire.diagnosis.diagnose import DiagnosisResult
from mftire.diagnosis.effects import WRITTEN_EVERY_ROW
from mftire.iotools.atomic import atomic_path, write_text_atomic
from mftire.iotools.output import safe_name
from mftire.iotools.tir import write_tir
from mftire.iotools.units import PLOT_UNITS, axis_label
from mftire.plotting import subplots

EXTENDED_TIR = "extended.tir"


def to_json(result: DiagnosisResult, extended_tir: str | None) -> dict:
    """The ``diagnosis.json`` document."""
    e = result.effect
    holdout = None
    if result.holdout is not None:
        holdout = dict(result.holdout)
        holdout["channels"] = {
            c.channel: {k: v for k, v in asdict(c).items() if k != "channel"} for c in result.errors
        }
    effect = None
    if e is not None and result.significant:
        effect = {
            "name": e.name,
            "variable": e.variable,
            "parameters": e.parameters,
            "physical": e.physical,
            "label": "physical model extension" if e.physical else "generic smooth correction (not physics)",
            "section": {k: v for k, v in e.section.items()},
            "targets": list(e.targets),
            "refitted_coefficients": e.standard,
            "training_residual_removed": e.removed,
            "messages": e.messages,
            "written": e.written,
        }
    return {
        "significant": bool(result.significant),
        "cause": result.cause if result.cause is not None else (
            result.ranking[0].variable if result.significant and result.ranking else None),
        "summary": result.summary(),
        "ranking": [
            {
                "variable": s.variable,
                "score": s.score,
                "p_value": s.p_value,
                "significant": s.significant,
                "channel": s.channel,
                "effect_size": s.effect,
                "derived": s.derived,
            }
            for s in result.ranking
        ],
        "effect": effect,
        "holdout": holdout,
        "extended_tir": extended_tir,
        "tried": [
            {"name": f.name, "variable": f.variable, "parameters": f.parameters, "bic": f.bic,
             "training_residual_removed": f.removed}
            for f in result.tried
        ],  # fmt: skip
        "messages": result.messages,
        "not_measured": dict(result.not_measured),
        "confounding": list(result.confounding),
        "profiles": _profiles_json(result),
    }


def _profiles_json(result: DiagnosisResult) -> dict | None:
    pr = result.profiles
    if pr is None:
        return None
    return {
        "factors": [{"factor": f.factor, "family": f.family, "channel": f.channel, "spread": f.spread,
                     "p_noise": f.chi2_p, "affected": bool(f.affected), "n_sweeps": int(len(f.values))}
                    for f in pr.factors],
        "links": [{"variable": lk.variable, "factor": lk.factor, "score": lk.score, "p_value": lk.p_value,
                   "r": lk.r, "confounded_with": lk.confounded_with, "within_block_p": lk.within_block_p}
                  for lk in pr.links[:20]],
    }  # fmt: skip


def _markdown(doc: dict) -> str:
    lines = ["# Diagnosis of the fit residual", "", f"**{doc['summary']}**", ""]
    lines += ["## Candidate ranking", "",
              "Share of the residual variance left by the MF inputs that each candidate explains "
              "(cross-validated by sweep), permutation p-value, and the size of the explained part "
              "(RMS, fraction of the channel's peak).", "",
              "| rank | variable | channel | score | p-value | effect size | significant |",
              "|---:|---|---|---:|---:|---:|---|"]  # fmt: skip
    for i, r in enumerate(doc["ranking"], 1):
        lines.append(
            f"| {i} | {r['variable']} | {r['channel']} | {r['score']:.3f} | {r['p_value']:.3f} | "
            f"{100 * r['effect_size']:.2f} % | {'yes' if r['significant'] else 'no'} |"
        )
    lines.append("")
    e = doc["effect"]
    if e is None:
        lines += ["## Effect", "", "No model change: " + "; ".join(doc["messages"] or ["no significant effect"]), ""]
    else:
        lines += ["## Effect", "", f"- **{e['name']}** in `{e['variable']}` — {e['label']}"]
        for k, v in e["parameters"].items():
            lines.append(f"  - `{k}` = {v:.6g}")
        if e["section"]:
            lines.append(f"- stored in `[MFTIRE_EXTENSIONS]` of `{doc['extended_tir']}`")
        lines.append(f"- refitted with it: {', '.join(sorted(e['refitted_coefficients'])) or 'none'}")
        lines.append(f"- training residual removed: {100 * e['training_residual_removed']:.1f} %")
        for m in e["messages"]:
            lines.append(f"- note: {m}")
        lines.append("")
    if doc.get("not_measured"):
        lines += ["## Channels left out", ""]
        lines += [f"- {ch}: {why}" for ch, why in doc["not_measured"].items()]
        lines.append("")
    pr = doc.get("profiles")
    if pr:
        lines += ["## Scaling-factor profiles", "",
                  "Each factor refitted per sweep with everything else held at the global fit; spread across sweeps "
                  "against the spread expected from noise (chi-squared), then the candidates that predict it "
                  "(leave-one-sweep-out, permutation p-value).", "",
                  "| factor | family | channel | spread | p (noise) | affected |", "|---|---|---|---:|---:|---|"]
        for f in pr["factors"]:
            lines.append(f"| {f['factor']} | {f['family']} | {f['channel']} | {f['spread']:.3g} | "
                         f"{f['p_noise']:.2g} | {'yes' if f['affected'] else 'no'} |")
        if pr["links"]:
            lines += ["", "| variable | factor | CV score | p-value | r |", "|---|---|---:|---:|---:|"]
            for lk in pr["links"][:10]:
                lines.append(f"| {lk['variable']} | {lk['factor']} | {lk['score']:.2f} | {lk['p_value']:.3f} | "
                             f"{lk['r']:+.2f} |")
        lines.append("")
    if doc.get("confounding"):
        lines += ["## Confounding", ""] + [f"- {c}" for c in doc["confounding"]] + [""]
    h = doc["holdout"]
    if h is not None and h.get("channels"):
        vals = ", ".join(f"{v:g}" for v in h["values"])
        lines += ["## Held-out condition", "",
                  f"{h['column']} = {vals} ({h['n_rows']} rows, not used in any fit). Before: the model "
                  "refitted without the law (the control), after: with it, both on the same training rows; "
                  f"the model written is {(doc.get('effect') or {}).get('written', WRITTEN_EVERY_ROW)}.", "",
                  "| channel | RMS before | RMS after | RMS % of peak before | after | residual variance removed |",
                  "|---|---:|---:|---:|---:|---:|"]  # fmt: skip
        for ch, c in h["channels"].items():
            lines.append(
                f"| {ch} | {c['rms_before']:.4g} | {c['rms_after']:.4g} | {c['rms_pct_before']:.2f} | "
                f"{c['rms_pct_after']:.2f} | {100 * c['variance_removed']:.1f} % |"
            )
        lines.append("")
    lines += ["## Figures", "", "- `ranking.png`: candidate scores",
              "- `residual_vs_<variable>.png`: residual against the top candidates (cause: before and after)",
              "- `curves_before_after.png`: held-out sweeps, data against the model before and after",
              "- `profile_<factor>.png`: per-sweep values of each affected scaling factor against the cause, with "
              "the fitted law", ""]  # fmt: skip
    return "\n".join(lines)


def _binned(x: np.ndarray, y: np.ndarray, n: int = 15):
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if len(np.unique(x)) <= n:
        xs = np.unique(x)
        return xs, np.array([y[x == v].mean() for v in xs])
    edges = np.quantile(x, np.linspace(0, 1, n + 1))
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n - 1)
    xs = np.array([x[idx == i].mean() if np.any(idx == i) else np.nan for i in range(n)])
    ys = np.array([y[idx == i].mean() if np.any(idx == i) else np.nan for i in range(n)])
    return xs, ys


def ranking_figure(ranking):
    """Bar chart of the candidates' scores, highest on top (red: significant)."""
    from matplotlib.patches import Patch

    fig, ax = subplots(figsize=(8, 0.35 * max(len(ranking), 4) + 1.4), constrained_layout=True)
    by_score = sorted(ranking, key=lambda r: r.score)  # highest score on top
    ax.barh([f"{_text(r.variable)} ({r.channel})" for r in by_score], [r.score for r in by_score],
            color=["tab:red" if r.significant else "tab:gray" for r in by_score])
    ax.set_xlabel("score: share of the residual variance explained beyond the MF inputs (CV) [-]")
    ax.set_ylabel("candidate variable (channel)")
    ax.set_title("candidates, sorted by score")
    ax.legend(handles=[Patch(color="tab:red", label="significant (permutation test)"),
                       Patch(color="tab:gray", label="not significant")], fontsize=8, loc="lower right")
    return fig


def before_after_figure(result: DiagnosisResult):
    """Every held-out sweep: data, the model before (dashed) and after (solid) per channel, against the
    swept slip; None without an effect or held-out rows."""
    if result.effect is None or result.train is None:
        return None
    df = result.data
    test = df[~result.train]
    chans = [c.channel for c in result.errors]
    if not chans or test.empty:
        return None
    from matplotlib.lines import Line2D

    sweeps = list(dict.fromkeys(test["sweep_id"]))  # every held-out sweep
    xcols = {sid: ("kappa" if test.loc[test["sweep_id"] == sid, "kappa"].std() >= test.loc[test["sweep_id"] == sid,
                                                                                                  "alpha"].std()
                   else "alpha") for sid in sweeps}  # fmt: skip
    xvars = sorted(set(xcols.values()))  # one column of panels per swept variable
    fig, axes = subplots(len(chans), len(xvars), figsize=(6.5 * len(xvars) + 2.6, 3.4 * len(chans)),
                         constrained_layout=True, squeeze=False)
    colors = [colormaps["viridis"](x) for x in np.linspace(0.05, 0.92, max(len(sweeps), 1))] if len(sweeps) > 10 \
        else [f"C{i}" for i in range(len(sweeps))]
    labels = {}
    for i, ch in enumerate(chans):
        for j, xcol in enumerate(xvars):
            ax = axes[i, j]
            for k, sid in enumerate(sweeps):
                if xcols[sid] != xcol:
                    continue
                g = test[test["sweep_id"] == sid].sort_values(xcol)
                x = g[xcol].to_numpy(float) * (np.degrees(1) if xcol == "alpha" else 1)
                ax.plot(x, g[ch], ".", color=colors[k], ms=4)
                ax.plot(x, g[ch] - g[f"residual_{ch}"], "--", color=colors[k], lw=1)
                ax.plot(x, g[ch] - g[f"residual_after_{ch}"], "-", color=colors[k], lw=1.2)
                labels[k] = _sweep_label(g, sid)
            ax.set_xlabel("α [deg]" if xcol == "alpha" else "κ [-]")
            ax.set_ylabel(f"{ch} [{PLOT_UNITS[ch]}]")
            ax.set_title(f"held-out sweeps: {ch} against {'α' if xcol == 'alpha' else 'κ'}")
            ax.grid(alpha=0.3)
    handles = [Line2D([], [], color=colors[k], lw=3, label=labels[k]) for k in sorted(labels)]
    handles += [Line2D([], [], color="k", marker=".", linestyle="none", label="data (held out)"),
                Line2D([], [], color="k", linestyle="--", label="model before (MF fit)"),
                Line2D([], [], color="k", linestyle="-", label="model after (MF + effect)")]
    fig.legend(handles=handles, loc="outside right center", fontsize=8, frameon=False)
    return fig


def _figures(result: DiagnosisResult, outdir: str) -> None:
    df = result.data
    ranking = result.ranking
    with atomic_path(os.path.join(outdir, "ranking.png")) as tmp:
        ranking_figure(ranking).savefig(tmp, format="png", dpi=100)

    for r in ranking[:3]:
        if r.variable not in df.columns or f"residual_{r.channel}" not in df.columns:
            continue
        x = df[r.variable].to_numpy(float)
        fig, ax = subplots(figsize=(7, 4.5), constrained_layout=True)
        y = df[f"residual_{r.channel}"].to_numpy(float)
        ax.plot(x, y, ".", ms=2, alpha=0.3, color="tab:blue")
        ax.plot(*_binned(x, y), "o-", color="tab:blue", label="before (binned mean)")
        after = f"residual_after_{r.channel}"
        if after in df.columns and result.effect is not None and r is ranking[0]:
            ya = df[after].to_numpy(float)
            ax.plot(x, ya, ".", ms=2, alpha=0.3, color="tab:orange")
            ax.plot(*_binned(x, ya), "s-", color="tab:orange", label="after (binned mean)")
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xlabel(_text(axis_label(r.variable)))
        ax.set_ylabel(f"{r.channel} data − model [{PLOT_UNITS[r.channel]}]")
        ax.set_title(f"residual of {r.channel} against {_text(r.variable)} (score {r.score:.2f})")
        ax.legend()
        # a column name is data, never a path (mftire.iotools.output.safe_name)
        with atomic_path(os.path.join(outdir, f"residual_vs_{safe_name(r.variable)}.png")) as tmp:
            fig.savefig(tmp, format="png", dpi=100)

    fig = before_after_figure(result)
    if fig is not None:
        with atomic_path(os.path.join(outdir, "curves_before_after.png")) as tmp:
            fig.savefig(tmp, format="png", dpi=100)


def _sweep_label(g, sid) -> str:
    """Legend text of a held-out sweep: its load, speed and pressure (set points when present)."""
    def v(col, setcol):
        return float(g[setcol].iloc[0]) if setcol in g else float(g[col].median())
    return (f"sweep {sid}: Fz {v('Fz', 'Fz_set'):.0f} N, {v('Vx', 'Vx_set') * 3.6:.0f} km/h, "
            f"{v('P', 'P_set') / 1e5:.3g} bar")


def write_report(result: DiagnosisResult, outdir: str | os.PathLike) -> dict:
    """Write diagnosis.md, diagnosis.json, the figures and (when there is an effect) the
    extended ``.tir`` into ``outdir``; return the JSON document."""
    outdir = os.fspath(outdir)
    os.makedirs(outdir, exist_ok=True)
    extended_name = None
    if result.significant and result.extended is not None:
        extended_name = EXTENDED_TIR
        write_tir(result.extended.parameters, os.path.join(outdir, EXTENDED_TIR))
    doc = to_json(result, extended_name)
    write_text_atomic(os.path.join(outdir, "diagnosis.json"), json.dumps(doc, indent=2, default=float) + "\n")
    write_text_atomic(os.path.join(outdir, "diagnosis.md"), _markdown(doc))
    _figures(result, outdir)
    if result.profiles is not None:
        from mftire.diagnosis.profile import plot_profiles

        plot_profiles(result, outdir)
    return doc


def _text(label: object) -> str:
    """A label from data as plain figure text: a ``$`` would start matplotlib's mathtext, and a very long
    name would squeeze the axes away."""
    text = str(label)
    text = text if len(text) <= 40 else text[:39] + "…"
    return text.replace("$", r"\$")
