"""Grouping a sweep table into sweeps: condition set points, sweep ids, kinds and directions.

:func:`group_sweeps` labels the rows of a validated sweep table (:mod:`mftire.iotools.sweeps`)
with operating-condition set points (1-D gap clustering, :func:`cluster_1d`) and sweep ids
(row order = measurement order); :func:`sweep_kind` tells pure longitudinal, pure lateral,
combined and free-rolling sweeps apart; :func:`summarize_sweeps` gives one row per sweep.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Sequence
from typing import Any

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.sweeps import REQUIRED_COLUMNS

__all__ = ["CONDITIONS", "KAPPA_TOL", "ALPHA_TOL", "cluster_1d", "condition_tolerances", "sweep_kind", "group_sweeps",
           "summarize_sweeps"]

#: Level tolerances of a held slip, kappa [-] and alpha [rad] (0.5 deg): the defaults of :func:`sweep_kind` and of
#: the two ways to cut sweeps that pass them on to it, :func:`group_sweeps` (sweep tables) and
#: :func:`mftire.segmentation.rig_segments.segment` (rig time series).
KAPPA_TOL = 0.01
ALPHA_TOL = math.radians(0.5)


def cluster_1d(values: Any, rel_tol: float = 0.0, abs_tol: float = 0.0) -> np.ndarray:
    """Single-linkage 1-D clustering by gaps.

    Sorted values are split wherever the gap between neighbours exceeds
    ``abs_tol + rel_tol * max(|left|, |right|)``. Dense noisy data around a set point
    (e.g. Fz = 4 kN +- 5 %) forms one cluster; set points further apart than the
    tolerance form separate ones.

    Parameters
    ----------
    values : array-like of float
    rel_tol : float
        Relative gap tolerance [-].
    abs_tol : float
        Absolute gap tolerance, in the unit of ``values``.

    Returns
    -------
    ndarray of int
        Cluster label per value, numbered 0.. in increasing value order; -1 for NaN.
    """
    x = np.asarray(values, dtype=float)
    labels = np.full(x.shape, -1, dtype=int)
    ok = np.isfinite(x)
    if not ok.any():
        return labels
    idx = np.flatnonzero(ok)
    order = idx[np.argsort(x[idx], kind="stable")]
    xs = x[order]
    gaps = np.diff(xs)
    thresh = abs_tol + rel_tol * np.maximum(np.abs(xs[:-1]), np.abs(xs[1:]))
    labels[order] = np.concatenate([[0], np.cumsum(gaps > thresh)])
    return labels


def set_point(values: np.ndarray, kind: str) -> float:
    """Representative set point of one cluster.

    Exact when all values are equal (simulation data). Otherwise the median, replaced by
    the roundest number within its uncertainty (3 standard errors, at most 1 % or
    0.05 deg), so that a load wandering around 4000 N is labelled 4000, not 4006.
    """
    v = values[np.isfinite(values)]
    if v.size == 0:
        return float("nan")
    if np.ptp(v) == 0:
        return float(v[0])
    med = float(np.median(v))
    sem = 3.0 * float(np.std(v)) / math.sqrt(v.size)
    if kind == "angle":
        med_deg = math.degrees(med)
        tol = min(0.05, math.degrees(sem))
        for decimals in range(0, 4):
            r = round(med_deg, decimals)
            if abs(r - med_deg) <= tol:
                return math.radians(r) if r != 0 else 0.0
        return med
    if med == 0:
        return 0.0
    tol = min(0.01 * abs(med), sem)
    magnitude = int(math.floor(math.log10(abs(med))))
    for sig in range(1, 7):
        r = round(med, sig - 1 - magnitude)
        if abs(r - med) <= tol:
            return float(r)
    return med


def _robust_range(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return 0.0
    if x.size < 20:
        return float(np.ptp(x))
    lo, hi = np.quantile(x, [0.02, 0.98])
    return float(hi - lo)


def sweep_kind(
    kappa: Any,
    alpha: Any,
    *,
    kappa_tol: float = KAPPA_TOL,
    alpha_tol: float = ALPHA_TOL,
) -> str:
    """Kind of a sweep from which slips vary.

    Parameters
    ----------
    kappa : array-like
        Longitudinal slip [-] of the sweep's rows.
    alpha : array-like
        Slip angle [rad] of the sweep's rows.
    kappa_tol, alpha_tol : float
        A slip "varies" when its (2-98 %) range exceeds twice the tolerance, and is
        "zero" when its median magnitude is within the tolerance.

    Returns
    -------
    str
        ``"pure_longitudinal"`` (kappa varies, alpha ~ 0), ``"pure_lateral"``
        (alpha varies, kappa ~ 0), ``"combined"`` (both varying, or one varying at a
        non-zero level of the other), or ``"free_rolling"`` (neither varies, both ~ 0).
        A constant non-zero slip point counts as pure of that slip if the other is 0.
    """
    k = np.asarray(kappa, dtype=float)
    a = np.asarray(alpha, dtype=float)
    k_var = _robust_range(k) > 2 * kappa_tol
    a_var = _robust_range(a) > 2 * alpha_tol
    k_zero = abs(float(np.nanmedian(k))) <= kappa_tol if k.size else True
    a_zero = abs(float(np.nanmedian(a))) <= alpha_tol if a.size else True
    if k_var and a_var:
        return "combined"
    if k_var:
        return "pure_longitudinal" if a_zero else "combined"
    if a_var:
        return "pure_lateral" if k_zero else "combined"
    if k_zero and a_zero:
        return "free_rolling"
    if a_zero:
        return "pure_longitudinal"
    if k_zero:
        return "pure_lateral"
    return "combined"


def _split_runs(
    kappa: np.ndarray, alpha: np.ndarray, kappa_tol: float, alpha_tol: float, patience: int = 3
) -> np.ndarray:
    """Split an ordered segment into runs in which one slip is held at a level.

    A run starts with both slips "held" at their level (the running mean of the run's
    values); the first slip to leave its level by more than the tolerance becomes the
    swept one, the other stays held; when the held slip leaves its level too, a new run
    starts. A slip only counts as having left its level when ``patience`` consecutive
    rows are out of it, so single noisy samples do not split a sweep.

    The level test alone finds a boundary late when the next sweep starts inside the held
    level (a braking sweep from kappa = 0 after a cornering sweep at kappa = 0: its first
    points are also "kappa held at 0"); :func:`_start_of_next_sweep` moves such a
    boundary back to where the swept slip of the run before stopped moving.  Finally a
    run is split where its swept slip jumps back (:func:`_reset_rows`): the same sweep
    measured again.
    """
    n = kappa.size
    run = np.zeros(n, dtype=int)
    r = 0

    def out_of_level(x: list[float], i: int, ref: float, tol: float) -> bool:
        if all(abs(v - ref) > tol for v in x[i : i + patience]):
            return True
        # a sweep of a few steps that returns to the level between them (alpha -7, 0, +3, +8, 0, -5 deg: a sparse
        # cornering sweep after a braking sweep at the same set points): the slip has left its level when this row
        # and most of the next 2 x patience rows lie beyond 3 x tol, far outside the noise of a held slip
        far = 3.0 * tol
        return abs(x[i] - ref) > far and sum(abs(v - ref) > far for v in x[i : i + 2 * patience]) >= patience

    k_arr, a_arr = kappa, alpha
    kappa, alpha = kappa.tolist(), alpha.tolist()  # row by row: Python floats are faster than numpy scalars
    k_sum, a_sum, count = kappa[0], alpha[0], 1
    held = "both"
    starts: list[int] = [0]
    swept: list[str | None] = []  # the swept slip of each finished run (None: not known)
    for i in range(1, n):
        k_ref, a_ref = k_sum / count, a_sum / count
        k_out = out_of_level(kappa, i, k_ref, kappa_tol)
        a_out = out_of_level(alpha, i, a_ref, alpha_tol)
        if held == "both":
            if k_out and a_out:
                new_run = True
            else:
                new_run = False
                if a_out:
                    held = "kappa"
                elif k_out:
                    held = "alpha"
        else:
            new_run = (held == "alpha" and a_out) or (held == "kappa" and k_out)
        if new_run:
            swept.append({"kappa": "alpha", "alpha": "kappa"}.get(held))
            starts.append(i)
            r += 1
            k_sum, a_sum, count, held = kappa[i], alpha[i], 1, "both"
        else:
            # running level of the held slip(s); noisy excursions are not averaged in
            if abs(kappa[i] - k_ref) <= kappa_tol:
                k_sum += kappa[i]
            else:
                k_sum += k_ref
            if abs(alpha[i] - a_ref) <= alpha_tol:
                a_sum += alpha[i]
            else:
                a_sum += a_ref
            count += 1
        run[i] = r
    swept.append({"kappa": "alpha", "alpha": "kappa"}.get(held))
    slips = {"kappa": (k_arr, kappa_tol), "alpha": (a_arr, alpha_tol)}
    # boundaries found late: move them back (one run at a time, in order)
    for r_new in range(1, len(starts)):
        var = swept[r_new - 1]
        if var is None:
            continue
        x, tol = slips[var]
        b = _start_of_next_sweep(x, starts[r_new - 1], starts[r_new], tol, patience)
        run[b : starts[r_new]] = r_new
        starts[r_new] = b
    # resets of the swept slip inside a run: a repeated sweep
    out = run.copy()
    extra = 0
    ends = [*starts[1:], n]
    for r_old, (s, e) in enumerate(zip(starts, ends, strict=True)):
        out[s:e] = r_old + extra
        var = swept[r_old]
        if var is None or e - s < 2 * patience:
            continue
        x, tol = slips[var]
        for b in _reset_rows(x[s:e], tol, patience):
            extra += 1
            out[s + b : e] = r_old + extra
    return out


def _start_of_next_sweep(x: np.ndarray, s: int, i: int, tol: float, patience: int) -> int:
    """First row of the run that the level test started at row ``i`` (run before it from row ``s``).

    ``x`` is the slip swept in the run before.  In the new run ``x`` is held, so rows
    before ``i`` where ``x`` already stands still at the new run's level belong to the
    new run, except the row that reached that level by an ordinary step of the sweep
    (its last point: a sweep that ends where the next one starts).  A row reached by a
    jump (a step beyond three typical steps and twice ``tol``) starts the new run.
    """
    level = float(np.median(x[i : i + patience]))
    steps = np.abs(np.diff(x[s : i + 1]))
    moving = steps[steps > 0]
    typical = float(np.median(moving)) if moving.size else 0.0  # the sweep's step (finer than tol or not)
    still = min(tol, 0.25 * typical)
    j = i
    while j - 1 > s and abs(x[j - 1] - level) <= tol and abs(x[j] - x[j - 1]) <= still:
        j -= 1
    if j == i or j - 1 < s:
        return i
    arrival = abs(x[j] - x[j - 1])
    if arrival > max(2 * tol, 3 * typical):
        return j  # jumped to the new level: the new sweep starts here
    return j + 1  # the sweep's own last point stays with it


def _reset_rows(x: np.ndarray, tol: float, patience: int) -> list[int]:
    """Rows (within one run) where the swept slip jumps back to repeat the sweep.

    A reset is a step against the sweep's direction just before it, larger than three
    typical steps and twice ``tol``, with at least ``patience`` rows on either side.  A
    turning point (the sweep reversing step by step) is not a reset, nor is a gap in a
    sweep (a large step in its own direction).
    """
    d = np.diff(x)
    steps = np.abs(d)
    moving = steps[steps > tol]
    if moving.size < 2:
        return []
    typical = float(np.median(moving))
    big = np.flatnonzero(steps > max(3 * typical, 2 * tol))
    out, last = [], 0
    for k in big:
        b = int(k) + 1
        before = d[:k][np.abs(d[:k]) > tol]
        if before.size == 0 or np.sign(before[-1]) == np.sign(d[k]):
            continue
        if b - last >= patience and x.size - b >= patience:
            out.append(b)
            last = b
    return out


def _merge_short_runs(run: np.ndarray, min_points: int) -> np.ndarray:
    """Merge runs shorter than ``min_points`` into the previous run (or the next one)."""
    ids, counts = np.unique(run, return_counts=True)
    if ids.size <= 1 or min_points <= 1:
        return run
    keep = {int(i) for i, c in zip(ids, counts, strict=True) if c >= min_points}
    if not keep:
        return np.zeros_like(run)
    mapping: dict[int, int] = {}
    last: int | None = None
    for i in ids:
        i = int(i)
        if i in keep:
            last = i
        mapping[i] = last if last is not None else -1
    first_kept = min(keep)
    out = np.array([mapping[int(i)] for i in run])
    out[out == -1] = first_kept
    return out


def _direction_labels(x: np.ndarray, tol: float) -> tuple[np.ndarray, str]:
    """Per-row direction (+1, -1, 0) of an ordered sweep variable and a summary word."""
    n = x.size
    if n < 2:
        return np.zeros(n, dtype=int), "none"
    smooth = pd.Series(x).rolling(5, center=True, min_periods=1).median().to_numpy()
    d = np.gradient(smooth)
    step = np.sign(d) * (np.abs(d) > 1e-3 * tol)
    dirs = step.astype(int)
    nz = dirs[dirs != 0]
    if nz.size == 0:
        return dirs, "none"
    frac_up = float(np.mean(nz > 0))
    if frac_up >= 0.9:
        return dirs, "increasing"
    if frac_up <= 0.1:
        return dirs, "decreasing"
    # compress into runs of one sign, ignoring short flickers
    runs: list[tuple[int, int]] = []
    for s in nz:
        if runs and runs[-1][0] == s:
            runs[-1] = (s, runs[-1][1] + 1)
        else:
            runs.append((int(s), 1))
    long_runs = [s for s, c in runs if c >= max(3, nz.size // 20)]
    merged = [s for i, s in enumerate(long_runs) if i == 0 or s != long_runs[i - 1]]
    names = {1: "increasing", -1: "decreasing"}
    if len(merged) == 2:
        return dirs, f"{names[merged[0]]}-{names[merged[1]]}"
    return dirs, "mixed"


#: The operating conditions that set a sweep's set points: (column, set-point column, how a set point is formed
#: from its rows, :func:`set_point`: ``"angle"`` for camber, ``"rel"`` otherwise).  One table for the sweep tables
#: (:func:`group_sweeps`) and the rig time series (:func:`mftire.segmentation.rig_segments.segment`).
CONDITIONS: tuple[tuple[str, str, str], ...] = (
    ("Fz", "Fz_set", "rel"),
    ("gamma", "gamma_set", "angle"),
    ("P", "P_set", "rel"),
    ("Vx", "Vx_set", "rel"),
)


def condition_tolerances(fz_tol: float, gamma_tol: float, p_tol: float, vx_tol: float,
                         vx_abs_tol: float) -> dict[str, tuple[float, float]]:
    """The (relative [-], absolute [SI]) gap tolerance of each of :data:`CONDITIONS` (:func:`cluster_1d`): load
    and pressure relative, camber absolute [rad], speed relative plus an absolute part [m/s] (a set point near
    standstill)."""
    return {"Fz": (fz_tol, 0.0), "gamma": (0.0, gamma_tol), "P": (p_tol, 0.0), "Vx": (vx_tol, vx_abs_tol)}


def group_sweeps(
    df: pd.DataFrame,
    fz_tol: float = 0.1,
    *,
    gamma_tol: float = math.radians(0.5),
    p_tol: float = 0.05,
    vx_tol: float = 0.1,
    vx_abs_tol: float = 0.5,
    kappa_tol: float = KAPPA_TOL,
    alpha_tol: float = ALPHA_TOL,
    by: Sequence[Hashable] | None = None,
    split: bool = True,
    min_points: int = 3,
) -> pd.DataFrame:
    """Label rows with operating-condition set points and sweep ids.

    Set points are found by 1-D gap clustering (:func:`cluster_1d`) of each condition
    over the whole table, so the same nominal load in two files gets the same
    ``Fz_set`` even when the measured Fz wanders around it.

    Sweeps are then found in row order (the measurement sequence): rows are split
    wherever the set points or the ``by`` columns change, and (``split=True``) wherever
    the slip that is held constant leaves its level (see ``kappa_tol``/``alpha_tol``),
    e.g. a kappa sweep at alpha = 0 followed by one at alpha = 4 deg. Runs shorter than
    ``min_points`` rows are merged into the previous run.

    Parameters
    ----------
    df : DataFrame
        Validated sweep table (SI).
    fz_tol : float
        Relative gap tolerance for Fz clustering [-]. The default 0.1 separates set
        points more than ~10 % apart, e.g. 2, 4, 6 kN with +-5 % noise.
    gamma_tol : float
        Absolute gap tolerance for camber [rad] (default 0.5 deg).
    p_tol : float
        Relative gap tolerance for pressure [-].
    vx_tol, vx_abs_tol : float
        Relative [-] and absolute [m/s] gap tolerance for speed.
    kappa_tol : float
        Level tolerance for kappa [-]: a held kappa may wander this much.
    alpha_tol : float
        Level tolerance for alpha [rad].
    by : sequence of column names, optional
        Columns that also delimit sweeps (e.g. a run id). Default: whichever of
        ``source`` and ``file`` exist.
    split : bool
        Split (condition, ``by``) runs further by held-slip level. With ``False``
        every contiguous run of constant set points and ``by`` values is one sweep.
    min_points : int
        Minimum rows per sweep before it is merged into its neighbour.

    Returns
    -------
    DataFrame
        Copy of ``df`` (same index and row order) with added columns:
        ``Fz_set, gamma_set, P_set, Vx_set`` (SI set points), ``sweep_id`` (int, in
        order of appearance), ``kind`` (see :func:`sweep_kind`), ``sweep_var``
        (``"kappa"``, ``"alpha"`` or ``"none"``), ``kappa_set``/``alpha_set`` (level of
        the held slip, NaN for the swept one), ``sweep_dir`` (per row +1/-1/0: is the
        sweep variable increasing) and ``direction`` (per sweep: ``increasing``,
        ``decreasing``, ``increasing-decreasing``, ``decreasing-increasing``,
        ``mixed`` or ``none``).
    """
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        raise MftireInputError(f"group_sweeps: missing column(s) {', '.join(missing)}")
    if len(df) == 0:
        raise MftireInputError("group_sweeps: empty table")
    out = df.copy()
    n = len(out)
    keys = np.zeros((n, 0), dtype=int)
    tols = condition_tolerances(fz_tol, gamma_tol, p_tol, vx_tol, vx_abs_tol)
    for col, set_col, kind in CONDITIONS:
        x = out[col].to_numpy(dtype=float)
        rel, ab = tols[col]
        labels = cluster_1d(x, rel_tol=rel, abs_tol=ab)
        centres = {lab: set_point(x[labels == lab], kind) for lab in np.unique(labels)}
        out[set_col] = np.array([centres[lab] for lab in labels], dtype=float)
        keys = np.column_stack([keys, labels])

    if by is None:
        by = [c for c in ("source", "file") if c in out.columns]
    for col in by:
        if col not in out.columns:
            raise MftireInputError(f"group_sweeps: 'by' column {col!r} not found")
        codes = pd.factorize(out[col], use_na_sentinel=False)[0]
        keys = np.column_stack([keys, codes])

    # contiguous segments of identical keys
    change = np.ones(n, dtype=bool)
    if n > 1:
        change[1:] = np.any(keys[1:] != keys[:-1], axis=1)
    kappa = out["kappa"].to_numpy(dtype=float)
    alpha = out["alpha"].to_numpy(dtype=float)
    sweep = np.zeros(n, dtype=int)
    next_id = 0
    starts = np.flatnonzero(change)
    ends = np.append(starts[1:], n)
    for s, e in zip(starts, ends, strict=True):
        if split and e - s > 1:
            runs = _split_runs(kappa[s:e], alpha[s:e], kappa_tol, alpha_tol)
            runs = _merge_short_runs(runs, min_points)
            _, runs = np.unique(runs, return_inverse=True)
        else:
            runs = np.zeros(e - s, dtype=int)
        sweep[s:e] = runs + next_id
        next_id += int(runs.max()) + 1

    out["sweep_id"] = sweep
    kinds = np.empty(n, dtype=object)
    svar = np.empty(n, dtype=object)
    k_set = np.full(n, np.nan)
    a_set = np.full(n, np.nan)
    sdir = np.zeros(n, dtype=int)
    direction = np.empty(n, dtype=object)
    order = np.argsort(sweep, kind="stable")
    bounds = np.flatnonzero(np.diff(sweep[order])) + 1
    for rows in np.split(order, bounds):
        k, a = kappa[rows], alpha[rows]
        kind = sweep_kind(k, a, kappa_tol=kappa_tol, alpha_tol=alpha_tol)
        if kind == "pure_longitudinal":
            var = "kappa" if _robust_range(k) > 2 * kappa_tol else "none"
        elif kind == "pure_lateral":
            var = "alpha" if _robust_range(a) > 2 * alpha_tol else "none"
        elif kind == "combined":
            rk, ra = _robust_range(k) / kappa_tol, _robust_range(a) / alpha_tol
            var = "kappa" if rk >= ra else "alpha"
            if max(rk, ra) <= 2:
                var = "none"
        else:
            var = "none"
        kinds[rows] = kind
        svar[rows] = var
        if var != "alpha":
            a_set[rows] = float(np.median(a))
        if var != "kappa":
            k_set[rows] = float(np.median(k))
        if var == "none":
            direction[rows] = "none"
        else:
            x = k if var == "kappa" else a
            dirs, word = _direction_labels(x, kappa_tol if var == "kappa" else alpha_tol)
            sdir[rows] = dirs
            direction[rows] = word
    out["kind"] = kinds
    out["sweep_var"] = svar
    out["kappa_set"] = k_set
    out["alpha_set"] = a_set
    out["sweep_dir"] = sdir
    out["direction"] = direction
    return out


def summarize_sweeps(grouped: pd.DataFrame) -> pd.DataFrame:
    """One row per sweep of a :func:`group_sweeps` result.

    Returns
    -------
    DataFrame
        Indexed by ``sweep_id`` with ``kind, sweep_var, direction, n, Fz_set, gamma_set,
        P_set, Vx_set, kappa_set, alpha_set, kappa_min, kappa_max, alpha_min,
        alpha_max`` and, when present, ``source``/``file`` of the first row.
    """
    need = ["sweep_id", "kind", "sweep_var", "direction", "Fz_set", "gamma_set", "P_set", "Vx_set"]
    missing = [c for c in need if c not in grouped.columns]
    if missing:
        raise MftireInputError(f"summarize_sweeps: run group_sweeps first (missing {missing})")
    g = grouped.groupby("sweep_id", sort=True)
    first_cols = ["kind", "sweep_var", "direction", "Fz_set", "gamma_set", "P_set", "Vx_set",
                  "kappa_set", "alpha_set"] + [c for c in ("source", "file") if c in grouped.columns]
    summary = g[first_cols].first()
    summary.insert(3, "n", g.size())
    summary["kappa_min"] = g["kappa"].min()
    summary["kappa_max"] = g["kappa"].max()
    summary["alpha_min"] = g["alpha"].min()
    summary["alpha_max"] = g["alpha"].max()
    return summary
