"""Rank candidate variables by the residual variance they explain beyond the MF inputs.

Method
------
The residual of a channel (data minus model) is projected on the direction of the
modelled value, r = (y − ŷ)·sign(ŷ), so that a change in friction shows with the
same sign on both sides of the characteristic (the raw Fy residual of a friction
change is odd in alpha), and divided by Fz (forces) or by Fz·R0 (moments), so that
residuals at different loads are comparable (a friction error is then a Δµ).
A k-nearest-neighbour regression predicts r from the Magic
Formula operating point alone — the *baseline* features |kappa|, |tan alpha|, gamma,
Fz/FNOMIN (slip magnitudes, so that left/right and drive/brake asymmetry remain for
the candidates ``sign_alpha`` and ``sign_kappa`` to explain) — and from the operating
point plus one candidate.  Both are scored by cross-validation grouped by sweep: a
whole sweep is predicted from the others, never a point from its neighbours in the
same sweep.  The score of a candidate is

    score = (MSE_baseline − MSE_with_candidate) / mean(r²),

the share of the residual variance it explains beyond what the MF inputs explain.

Significance is a permutation test that keeps the structure of the candidate: a
sweep-level candidate (constant within sweeps) has its sweep values shuffled among
sweeps; a candidate that varies within sweeps is shifted circularly along the
sequence.  The p-value is (1 + #null scores >= score)/(1 + n).  A candidate is
*significant* when p <= ``alpha`` (0.05) **and** the effect is large enough to
matter: score >= ``min_score`` and the RMS of the part it explains >= ``min_effect``
(1 %) of the channel's peak.  A significant candidate is only reported as an effect
when a model term fitted for it also beats a control refit (see
:mod:`mftire.diagnosis.effects`), so noise and artefacts too small to matter are not
reported.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from mftire.diagnosis.candidates import Candidate

MOMENTS = ("Mz", "Mx", "My")


@dataclass
class CandidateScore:
    """The score of one candidate (its best channel)."""

    variable: str
    channel: str
    score: float  #: share of residual variance explained beyond the MF inputs [-]
    p_value: float
    significant: bool
    effect: float  #: RMS of the explained part / channel peak [-]
    sweep_level: bool
    derived: bool
    channel_scores: dict[str, float] = field(default_factory=dict)  #: score on every channel [-]

    def to_dict(self) -> dict:
        return asdict(self)


def normalised_residual(channel: str, y: np.ndarray, y_model: np.ndarray, Fz: np.ndarray, R0: float) -> np.ndarray:
    """Residual along the modelled value, per unit load [-].

    (y − ŷ)·sign(ŷ) divided by Fz for forces and by Fz·R0 for moments.
    """
    scale = Fz * R0 if channel in MOMENTS else Fz
    direction = np.where(y_model == 0.0, 1.0, np.sign(y_model))
    return (y - y_model) * direction / np.maximum(scale, 1e-9)


def baseline_features(
    kappa: np.ndarray, alpha: np.ndarray, gamma: np.ndarray, Fz: np.ndarray, Fz0: float
) -> np.ndarray:
    """Operating-point features of the baseline regression (slip magnitudes, camber, load)."""
    return np.column_stack([np.abs(kappa), np.abs(np.tan(alpha)), gamma, Fz / Fz0])


def _standardise(X: np.ndarray) -> np.ndarray:
    s = np.nanstd(X, axis=0)
    s[~(s > 0)] = 1.0
    return (X - np.nanmean(X, axis=0)) / s


def fold_of_groups(groups: np.ndarray, n_folds: int, seed: int = 0) -> np.ndarray:
    """Assign every row to a fold so that each group (sweep) lies in one fold."""
    uniq = np.unique(groups)
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(uniq))
    fold_of = {g: i % n_folds for i, g in zip(order, uniq, strict=True)}
    return np.array([fold_of[g] for g in groups])


def cv_predict(X: np.ndarray, r: np.ndarray, folds: np.ndarray, k: int = 12) -> np.ndarray:
    """Out-of-fold k-nearest-neighbour predictions of r from features X."""
    pred = np.empty_like(r)
    for f in np.unique(folds):
        test = folds == f
        train = ~test
        kk = min(k, int(train.sum()))
        tree = cKDTree(X[train])
        _, idx = tree.query(X[test], k=kk)
        idx = idx.reshape(int(test.sum()), kk)
        pred[test] = r[train][idx].mean(axis=1)
    return pred


def _score(X0: np.ndarray, c: np.ndarray, r: np.ndarray, folds: np.ndarray, mse0: float, denom: float):
    X = np.column_stack([X0, c])
    pred = cv_predict(X, r, folds)
    return 1.0 - float(np.mean((r - pred) ** 2)) / mse0, pred


def _null_values(c: Candidate, values: np.ndarray, groups: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Candidate values under the null: sweeps exchange their trajectories.

    Sweep i receives the values of sweep perm(i), linearly resampled over the
    normalised position in the sweep, so within-sweep shape is kept and the link
    between a sweep's candidate values and its residual is broken.
    """
    uniq, inv = np.unique(groups, return_inverse=True)
    rows = [np.flatnonzero(inv == g) for g in range(len(uniq))]
    perm = rng.permutation(len(uniq))
    out = np.empty_like(values)
    for i, src in zip(range(len(uniq)), perm, strict=True):
        dst_rows, src_vals = rows[i], values[rows[src]]
        if len(src_vals) == len(dst_rows):
            out[dst_rows] = src_vals
        else:
            xs = np.linspace(0.0, 1.0, len(src_vals))
            out[dst_rows] = np.interp(np.linspace(0.0, 1.0, len(dst_rows)), xs, src_vals)
    return out


def rank_candidates(
    residuals: Mapping[str, np.ndarray],
    peaks: Mapping[str, float],
    X0: np.ndarray,
    cands: Sequence[Candidate],
    groups: np.ndarray,
    *,
    n_folds: int = 5,
    n_perm: int = 99,
    alpha: float = 0.05,
    min_score: float = 0.05,
    min_effect: float = 0.01,
    max_points: int = 4000,
    seed: int = 0,
) -> list[CandidateScore]:
    """Score every candidate on every channel; return one entry per candidate, best first.

    Parameters
    ----------
    residuals : mapping channel -> array
        Normalised residuals (see :func:`normalised_residual`); NaN rows are ignored.
    peaks : mapping channel -> float
        Peak |channel| per unit load, to express the effect size [-].
    X0 : ndarray (n, m)
        Baseline features (:func:`baseline_features`).
    cands : sequence of Candidate
    groups : ndarray
        Sweep id of every row (cross-validation and permutation groups).
    """
    rng = np.random.default_rng(seed)
    n = len(groups)
    keep = np.arange(n)
    if n > max_points:
        keep = np.sort(rng.choice(n, size=max_points, replace=False))
    results: list[CandidateScore] = []
    per_channel: dict[str, tuple] = {}
    for ch, r_all in residuals.items():
        r = np.asarray(r_all, float)[keep]
        ok = np.isfinite(r)
        if ok.sum() < 3 * n_folds:
            continue
        g = groups[keep][ok]
        if len(np.unique(g)) < n_folds:
            continue
        Xb = _standardise(X0[keep][ok])
        folds = fold_of_groups(g, n_folds, seed)
        pred0 = cv_predict(Xb, r[ok], folds)
        mse0 = float(np.mean((r[ok] - pred0) ** 2)) or 1e-300
        denom = mse0
        per_channel[ch] = (ok, Xb, folds, pred0, mse0, denom, r[ok], g)

    for c in cands:
        best: CandidateScore | None = None
        channel_scores: dict[str, float] = {}
        for ch, (ok, Xb, folds, pred0, mse0, denom, r, g) in per_channel.items():
            v = c.values[keep][ok]
            if not np.all(np.isfinite(v)) or np.std(v) == 0:
                continue
            cs = (v - v.mean()) / v.std()
            s, pred = _score(Xb, cs, r, folds, mse0, denom)
            channel_scores[ch] = s
            effect = float(np.sqrt(np.mean((pred - pred0) ** 2))) / max(peaks.get(ch, 1.0), 1e-9)
            entry = CandidateScore(c.name, ch, s, 1.0, False, effect, c.sweep_level, c.derived)
            if best is None or entry.score > best.score:
                best = entry
                best_ctx = (Xb, folds, mse0, denom, r, g, v)
        if best is None:
            continue
        best.channel_scores = channel_scores
        if best.score >= min_score and best.effect >= min_effect:
            Xb, folds, mse0, denom, r, g, v = best_ctx
            exceed = 0
            done = 0
            for _ in range(n_perm):
                vn = _null_values(c, v, g, rng)
                cs = (vn - vn.mean()) / (vn.std() or 1.0)
                s_null, _ = _score(Xb, cs, r, folds, mse0, denom)
                done += 1
                exceed += s_null >= best.score
                if exceed > alpha * (n_perm + 1):  # cannot become significant any more
                    break
            best.p_value = (1 + exceed) / (1 + done)
            best.significant = best.p_value <= alpha
        results.append(best)
    results.sort(key=lambda e: (e.significant, e.score), reverse=True)
    return results
