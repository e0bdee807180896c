"""Rank candidate variables by the residual variance they explain beyond the MF inputs.

Method
------
The residual of a channel (data minus model) is scored in two forms (:func:`residual_forms`), each divided
by Fz (forces) or by Fz·R0 (moments), so that residuals at different loads are comparable (a friction error
is then a Δµ):

* along the modelled value, r = (y − ŷ)·sign(ŷ), so that a change in friction, stiffness or shape shows with
  the same sign on both sides of the characteristic (the raw Fy residual of a friction change is odd in alpha);
* raw, r = y − ŷ, so that a shift or an offset (of the force, the slip angle, the camber) shows with the same
  sign on both sides.  The candidates odd in the slip (:data:`SIGN_CANDIDATES`) are not scored on it.

A k-nearest-neighbour regression predicts r from the Magic Formula operating point alone — the *baseline*
features |kappa|, |tan alpha|, gamma, Fz/FNOMIN (slip magnitudes, so that left/right and drive/brake
asymmetry remain for the candidates ``sign_alpha`` and ``sign_kappa`` to explain) — and from the operating
point plus one candidate.  Both are scored by cross-validation grouped by unit: a whole unit is predicted
from the others, never a point from its neighbours in the same unit.  The units are the runs (consecutive sweeps
at one operating condition, :func:`mftire.diagnosis.diagnose.condition_runs`), else the sweeps: the sweeps of a
run share its scatter (the mounting, the warm-up), and a column constant in a run would otherwise "explain" it
from the run's other sweeps.  The score of a candidate is

    score = (MSE_baseline − MSE_with_candidate) / MSE_baseline,

the share of the residual variance it explains beyond what the MF inputs explain.

Significance is a permutation test that keeps the structure of the candidate: units exchange their
trajectories of the candidate (:func:`_null_values`).  A candidate is tested on its best-scoring residuals in
turn (channels and forms, at most :data:`MAX_TESTS`) where it explains at least :data:`MIN_SCORE` of the
variance and an RMS of at least :data:`MIN_EFFECT` of the channel's peak.  Its p-value is the larger of the
permutation p-value (1 + #null scores >= score)/(1 + n) and the Bonferroni-corrected normal tail of its score
among the null scores (corrected over the effective number of candidates tested, :func:`effective_tests`: the
first of many candidates is not held to one test's level).  It is *significant* when that p-value <= ``alpha``
(0.05).  The normal tail is only an approximation, and a conservative one where the null scores spread wide (a
drift over loads tested in blocks): when no candidate is significant, the strongest test that no null score
reached is run on to :data:`UNBEATEN_PERMUTATIONS` × (effective tests)/alpha permutations, and its permutation
p-value corrected over the effective tests (Bonferroni) decides.  A significant candidate is only reported as an
effect when a model term fitted for it also beats a control refit (see :mod:`mftire.diagnosis.effects`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np
from scipy import stats
from scipy.spatial import cKDTree

from mftire.diagnosis.candidates import SIGN_CANDIDATES, Candidate

MOMENTS = ("Mz", "Mx", "My")
#: Smallest effect reported: RMS of the explained part over the channel's peak [-].  Significance is the
#: permutation test's; this only keeps effects too small to matter out (a tenth of a per cent of the peak: an
#: aligning-moment effect of a slip-angle or camber offset is a few tenths of a per cent of the peak Mz, and the
#: cross-validated neighbour prediction that measures it is smoothed.  At 0.25 % four of the zoo's 150 effect draws
#: went unreported; at 0.1 % its 50 null draws gain no significant candidate).
MIN_EFFECT = 0.001
#: Smallest share of the residual variance a candidate must explain beyond the MF inputs to be tested [-].
#: On campaigns without an effect (run-to-run scatter, decoys drifting with time or load) the first candidate
#: explains up to ~7 %; the permutation null alone is not tight enough there.
MIN_SCORE = 0.1
#: A candidate is tested on at most this many of its best-scoring residuals (channels and forms).
MAX_TESTS = 3
#: When nothing is significant, the strongest test that no null score reached is run on until this many times
#: (effective tests)/alpha permutations (:func:`rank_candidates`): its corrected permutation p-value then
#: reaches alpha/2 with no null score above it, alpha with one.
UNBEATEN_PERMUTATIONS = 2


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
    raw: bool = False  #: scored on the raw residual (a shift or offset), not along the model (:func:`residual_forms`)

    def to_dict(self) -> dict:
        return asdict(self)


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
    """Assign every row to a fold so that each group (run or sweep) lies in one fold."""
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


def _score(X0: np.ndarray, c: np.ndarray, r: np.ndarray, folds: np.ndarray, mse0: float):
    X = np.column_stack([X0, c])
    pred = cv_predict(X, r, folds)
    return 1.0 - float(np.mean((r - pred) ** 2)) / mse0, pred


def _null_values(c: Candidate, values: np.ndarray, groups: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Candidate values under the null: units (runs or sweeps, ``groups``) exchange their trajectories.

    Unit i receives the values of unit perm(i), linearly resampled over the
    normalised position in the unit, so within-unit shape is kept and the link
    between a unit's candidate values and its residual is broken.
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


#: Residual forms (:func:`residual_forms`): along the modelled value, and as measured.
RAW = "raw"


def residual_forms(channel: str, y: np.ndarray, y_model: np.ndarray, Fz: np.ndarray,
                   R0: float) -> dict[str, np.ndarray]:
    """The two forms of a channel's normalised residual that the ranking scores [-]:

    * ``channel:raw``: as measured, (y − ŷ) divided by Fz for forces and by Fz·R0 for moments, where a shift or
      an offset (of the force, of the slip angle, of the camber; Pacejka 2012 eqs 4.E20, 4.E27-4.E29) shows
      with one sign on both sides;
    * ``channel``: along the modelled value, the raw form times sign(ŷ), where a change of grip, stiffness or
      shape shows with one sign on both sides of the characteristic.
    """
    raw = (y - y_model) / np.maximum(Fz * R0 if channel in MOMENTS else Fz, 1e-9)
    return {channel: raw * np.where(y_model == 0.0, 1.0, np.sign(y_model)), f"{channel}:{RAW}": raw}


def _null_scores(c: Candidate, v: np.ndarray, ctx: tuple, score: float, n_perm: int, limit: float,
                 rng: np.random.Generator) -> list[float]:
    """Null scores of ``c`` (:func:`_null_values`), at most ``n_perm``; stops once more than ``limit`` of them reach
    ``score`` (it cannot become significant any more)."""
    Xb, folds, mse0, r, g = ctx
    nulls: list[float] = []
    exceed = 0
    for _ in range(n_perm):
        vn = _null_values(c, v, g, rng)
        cs = (vn - vn.mean()) / (vn.std() or 1.0)
        s_null, _ = _score(Xb, cs, r, folds, mse0)
        nulls.append(s_null)
        exceed += s_null >= score
        if exceed > limit:
            break
    return nulls


def _null_test(c: Candidate, v: np.ndarray, ctx: tuple, score: float, n_perm: int, alpha: float,
               rng: np.random.Generator) -> tuple[float, float, int]:
    """Permutation p-value of ``score``, the normal tail of its z-score in the null scores and how many null
    scores reached it [-, -, -]."""
    nulls = _null_scores(c, v, ctx, score, n_perm, alpha * (n_perm + 1), rng)
    exceed = int(np.sum(np.asarray(nulls) >= score))
    p_perm = (1 + exceed) / (1 + len(nulls))
    sd = float(np.std(nulls))
    tail = float(stats.norm.sf((score - float(np.mean(nulls))) / sd)) if sd > 0 else 0.0
    return p_perm, tail, exceed


def effective_tests(values: Sequence[np.ndarray]) -> float:
    """Effective number of independent tests among candidates with these values [-] (Li & Ji 2005): from the
    eigenvalues λ of their correlation matrix, Σ [λ >= 1] + (λ − floor(λ)).  Candidates that drift together
    (time, the position in the sequence, the friction work, a temperature following them) count about once."""
    if len(values) <= 1:
        return 1.0
    X = np.column_stack([np.asarray(v, float) for v in values])
    X = X[np.all(np.isfinite(X), axis=1)]
    sd = X.std(axis=0)
    if X.shape[0] < 3 or np.any(sd == 0):
        return float(len(values))
    lam = np.abs(np.linalg.eigvalsh(np.corrcoef(X, rowvar=False)))
    return max(1.0, float(np.sum((lam >= 1.0) + (lam - np.floor(lam)))))


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
    min_score: float = MIN_SCORE,
    min_effect: float = MIN_EFFECT,
    max_points: int = 4000,
    seed: int = 0,
) -> list[CandidateScore]:
    """Score every candidate on every channel; return one entry per candidate, best first.

    Parameters
    ----------
    residuals : mapping name -> array
        Normalised residuals (:func:`residual_forms`: a channel's name, or ``"Fy:raw"`` for its raw form); NaN
        rows are ignored.
    peaks : mapping channel -> float
        Peak |channel| per unit load, to express the effect size [-].
    X0 : ndarray (n, m)
        Baseline features (:func:`baseline_features`).
    cands : sequence of Candidate
    groups : ndarray
        Unit of every row, the run or the sweep (cross-validation and permutation groups).

    A candidate is tested on its best-scoring residuals in turn (at most :data:`MAX_TESTS`), and reported with
    the first on which it is significant, else with its best.  Its p-value is the larger of the permutation
    p-value and the Bonferroni-corrected normal tail of its score in the null scores (the correction over the
    candidates large enough to be tested: the first of many candidates is not held to one test's level).  When
    none is significant, the strongest test no null score reached gets more permutations (module docstring).
    """
    rng = np.random.default_rng(seed)
    n = len(groups)
    keep = np.arange(n)
    if n > max_points:
        keep = np.sort(rng.choice(n, size=max_points, replace=False))
    per_key: dict[str, tuple] = {}
    for key, r_all in residuals.items():
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
        per_key[key] = (ok, Xb, folds, pred0, mse0, r[ok], g)

    # every candidate on every residual
    scored: list[tuple[Candidate, list[tuple[CandidateScore, tuple, np.ndarray]], dict[str, float]]] = []
    for c in cands:
        entries = []
        channel_scores: dict[str, float] = {}
        for key, (ok, Xb, folds, pred0, mse0, r, g) in per_key.items():
            v = c.values[keep][ok]
            if not np.all(np.isfinite(v)) or np.std(v) == 0:
                continue
            ch = key.split(":")[0]
            if key != ch and c.name in SIGN_CANDIDATES:
                continue
            s, pred = _score(Xb, (v - v.mean()) / v.std(), r, folds, mse0)
            channel_scores[ch] = max(s, channel_scores.get(ch, -np.inf))
            effect = float(np.sqrt(np.mean((pred - pred0) ** 2))) / max(peaks.get(ch, 1.0), 1e-9)
            entry = CandidateScore(c.name, ch, s, 1.0, False, effect, c.sweep_level, c.derived, raw=key != ch)
            entries.append((entry, (Xb, folds, mse0, r, g), v))
        if entries:
            entries.sort(key=lambda t: t[0].score, reverse=True)
            scored.append((c, entries, channel_scores))

    def testable(e: CandidateScore) -> bool:
        return e.score >= min_score and e.effect >= min_effect

    n_tested = effective_tests([c.values[keep] for c, entries, _ in scored if any(testable(e) for e, _, _ in entries)])
    results: list[CandidateScore] = []
    #: (score, candidate, entry, its context, values) of the tests no null score reached that the correction refused
    unbeaten: list[tuple] = []
    for c, entries, channel_scores in scored:
        best = entries[0][0]
        for entry, ctx, v in [t for t in entries if testable(t[0])][:MAX_TESTS]:
            p_perm, tail, exceed = _null_test(c, v, ctx, entry.score, n_perm, alpha, rng)
            entry.p_value = max(p_perm, min(1.0, n_tested * tail))
            entry.significant = entry.p_value <= alpha
            if entry.significant or best.p_value == 1.0:
                best = entry
            if entry.significant:
                break
            if exceed == 0:
                unbeaten.append((entry.score, c, entry, ctx, v))
        best.channel_scores = channel_scores
        results.append(best)
    if unbeaten and not any(e.significant for e in results):
        # the strongest candidate that no null score reached, but whose normal tail the correction refused (the
        # null scores of a drift over blocked loads spread wide): more permutations, until the permutation p-value
        # alone, corrected over the effective number of tests (Bonferroni), can decide
        _, c, entry, ctx, v = max(unbeaten, key=lambda t: t[0])
        total = int(np.ceil(UNBEATEN_PERMUTATIONS * n_tested / alpha))  # floor of the corrected p: alpha / 2
        nulls = _null_scores(c, v, ctx, entry.score, max(total - n_perm, 0), alpha / n_tested * (total + 1), rng)
        exceed = int(np.sum(np.asarray(nulls) >= entry.score))
        p_more = min(1.0, n_tested * (1 + exceed) / (1 + n_perm + len(nulls)))
        if p_more < entry.p_value:
            entry.p_value = p_more
            entry.significant = p_more <= alpha
            i = next(i for i, e in enumerate(results) if e.variable == c.name)
            if entry is not results[i]:
                entry.channel_scores = results[i].channel_scores
                results[i] = entry
    results.sort(key=lambda e: (e.significant, e.score), reverse=True)
    return results
