"""diagnosis.md, diagnosis.json and figures of a :class:`DiagnosisResult`."""

from __future__ import annotations

import json
import os
from dataclasses import asdict

import numpy as np

from mftire.diagnosis.diagnose import DiagnosisResult
from mftire.iotools.atomic import atomic_path, write_text_atomic
from mftire.iotools.tir import write_tir
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
                  "the model written is the law refitted on every row.", "",
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


def _figures(result: DiagnosisResult, outdir: str) -> None:
    df = result.data
    ranking = result.ranking
    fig, ax = subplots(figsize=(8, 0.35 * max(len(ranking), 4) + 1.2), constrained_layout=True)
    names = [f"{r.variable} ({r.channel})" for r in ranking][::-1]
    scores = [r.score for r in ranking][::-1]
    colors = ["tab:red" if r.significant else "tab:gray" for r in ranking][::-1]
    ax.barh(names, scores, color=colors)
    ax.set_xlabel("share of residual variance explained beyond the MF inputs (CV)")
    ax.set_title("candidates (red: significant)")
    with atomic_path(os.path.join(outdir, "ranking.png")) as tmp:
        fig.savefig(tmp, format="png", dpi=100)

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
        ax.set_xlabel(r.variable)
        ax.set_ylabel(f"{r.channel} data − model")
        ax.set_title(f"residual of {r.channel} against {r.variable} (score {r.score:.2f})")
        ax.legend()
        with atomic_path(os.path.join(outdir, f"residual_vs_{r.variable}.png")) as tmp:
            fig.savefig(tmp, format="png", dpi=100)

    if result.effect is None or result.train is None:
        return
    test = df[~result.train]
    chans = [c.channel for c in result.errors]
    if not chans:
        return
    sweeps = list(dict.fromkeys(test["sweep_id"]))[:6]
    fig, axes = subplots(len(chans), 1, figsize=(9, 3.2 * len(chans)), constrained_layout=True, squeeze=False)
    for ax, ch in zip(axes[:, 0], chans, strict=True):
        for i, sid in enumerate(sweeps):
            g = test[test["sweep_id"] == sid]
            xcol = "kappa" if g["kappa"].std() > g["alpha"].std() else "alpha"
            x = g[xcol].to_numpy(float) * (np.degrees(1) if xcol == "alpha" else 1)
            color = f"C{i}"
            ax.plot(x, g[ch], ".", color=color, ms=4)
            ax.plot(x, g[ch] - g[f"residual_{ch}"], "--", color=color, lw=1)
            ax.plot(x, g[ch] - g[f"residual_after_{ch}"], "-", color=color, lw=1.2)
        ax.set_ylabel(ch)
        ax.set_title(f"held-out sweeps: points data, dashed before, solid after ({ch})")
    with atomic_path(os.path.join(outdir, "curves_before_after.png")) as tmp:
        fig.savefig(tmp, format="png", dpi=100)


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
