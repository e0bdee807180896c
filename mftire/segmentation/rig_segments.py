"""Cutting a continuous rig time series into sweeps (:func:`segment`), and the one-call import.

The readers (:func:`~mftire.iotools.rig.read_ttc`, :func:`~mftire.iotools.rig.read_columns`)
give an SI/ISO time series; :func:`segment` finds the steady condition levels and the
slip sweeps in it (procedure: the "Segmentation" section of :mod:`mftire.iotools.rig`);
:func:`import_rig` reads, segments and writes the sweep CSV (``mftire import``).
"""

from __future__ import annotations

import math
import os
import time as _time
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
import pandas as pd

from mftire.errors import MftireInputError
from mftire.iotools.columns import SET_POINT_COLUMNS
from mftire.iotools.rig import ColumnSpec, PathLike, read_raw, write_sweeps
from mftire.iotools.sweeps import REQUIRED_COLUMNS
from mftire.segmentation.grouping import (
    ALPHA_TOL,
    CONDITIONS,
    KAPPA_TOL,
    cluster_1d,
    condition_tolerances,
    set_point,
    sweep_kind,
)

__all__ = ["RigReport", "segment", "import_rig"]

#: The conditions of :data:`~mftire.segmentation.grouping.CONDITIONS` in the order their changes name a left-out
#: row's reason (a load ramp first)
_CONDITIONS = ("Fz", "P", "gamma", "Vx")
_SET_POINT_KIND = {col: kind for col, _, kind in CONDITIONS}
_REASON_NAMES = {"Fz": "load ramp", "P": "pressure change", "gamma": "inclination change", "Vx": "speed change"}


@dataclass
class RigReport:
    """What :func:`segment` (and :func:`import_rig`) did."""

    file: str = ""
    n_rows: int = 0
    duration_s: float = 0.0
    sample_rate_hz: float = 0.0
    convention: str = ""
    units_read: dict[str, str] = field(default_factory=dict)
    channel_map: dict[str, str] = field(default_factory=dict)
    levels: dict[str, list[float]] = field(default_factory=dict)  #: levels found per condition (SI)
    rows_kept: int = 0
    dropped: dict[str, int] = field(default_factory=dict)  #: rows dropped per reason
    segments: list[dict[str, Any]] = field(default_factory=list)  #: one entry per segment, kept or dropped
    n_sweeps: int = 0
    n_points: int = 0
    directions: dict[str, int] = field(default_factory=dict)  #: sweeps per direction
    messages: list[str] = field(default_factory=list)
    seconds: float = 0.0

    def to_dict(self) -> dict[str, Any]:
        """Plain-dict copy (JSON serialisable)."""
        return asdict(self)

    def __str__(self) -> str:
        return self.text()

    def text(self, max_listed: int = 20) -> str:
        """Human-readable summary, listing at most ``max_listed`` dropped segments."""
        lines = [f"{self.file}: {self.n_rows} rows, {self.duration_s:.1f} s at {self.sample_rate_hz:.4g} Hz, "
                 f"{self.convention.upper()} axes -> ISO W"]
        for c, lv in self.levels.items():
            shown = ", ".join(_fmt_level(c, v) for v in lv)
            lines.append(f"  {c} levels: {shown}")
        kept = sum(1 for s in self.segments if s["status"] == "kept")
        lines.append(f"  {kept} of {len(self.segments)} segments kept, {self.rows_kept} rows in "
                     f"{self.n_sweeps} sweeps ({', '.join(f'{n} {d}' for d, n in self.directions.items())}) "
                     f"-> {self.n_points} points")
        for reason, n in sorted(self.dropped.items(), key=lambda kv: -kv[1]):
            lines.append(f"  dropped {n} rows ({n / max(self.n_rows, 1):.1%}): {reason}")
        dropped = [s for s in self.segments if s["status"] != "kept"]
        for s in dropped[:max_listed]:
            lines.append(f"    t = {s['t_start']:.2f}-{s['t_end']:.2f} s (rows {s['row_first']}-{s['row_last']}):"
                         f" {s['reason']}")
        if len(dropped) > max_listed:
            lines.append(f"    ... {len(dropped) - max_listed} more dropped segments (see the JSON report)")
        lines.extend(f"  note: {m}" for m in self.messages)
        return "\n".join(lines)


def _fmt_level(column: str, v: float) -> str:
    if column == "gamma":
        return f"{math.degrees(v):.2f} deg"
    if column == "P":
        return f"{v / 1e3:.1f} kPa"
    if column == "Vx":
        return f"{v * 3.6:.1f} km/h"
    return f"{v:.0f} N"


def _tol(column: str, level: np.ndarray, tols: Mapping[str, tuple[float, float]]) -> np.ndarray:
    rel, ab = tols[column]
    return ab + rel * np.abs(level)


def _runs(codes: np.ndarray) -> np.ndarray:
    """Run id of each element: increments wherever the code changes."""
    change = np.empty(codes.size, dtype=bool)
    if codes.size:
        change[0] = True
        change[1:] = codes[1:] != codes[:-1]
    return np.cumsum(change) - 1


def segment(
    df: pd.DataFrame,
    *,
    time: str | None = None,
    fz_tol: float = 0.05,
    p_tol: float = 0.03,
    gamma_tol: float = math.radians(0.3),
    vx_tol: float = 0.05,
    vx_abs_tol: float = 0.3,
    alpha_tol: float = ALPHA_TOL,
    kappa_tol: float = KAPPA_TOL,
    smooth_s: float = 0.5,
    hold_s: float = 1.0,
    min_segment_s: float = 3.0,
    min_sweep_points: int = 10,
    min_dwell_s: float = 0.3,
    warmup: str | float | None = "auto",
    points_per_sweep: int | None = None,
    keep_dropped: bool = True,
    name: str = "",
) -> tuple[pd.DataFrame, RigReport]:
    """Cut a continuous SI/ISO time series (from :func:`read_ttc` / :func:`read_columns`) into sweeps.

    See the module docstring for the procedure.  Tolerances: ``fz_tol``, ``p_tol`` and
    ``vx_tol`` relative [-] (``vx_abs_tol`` [m/s] added), ``gamma_tol`` and
    ``alpha_tol`` [rad], ``kappa_tol`` [-].  Times in seconds.  A sweep has at least
    ``min_sweep_points`` rows; the swept slip standing still (within a tenth of its
    tolerance over 0.1 s) for ``min_dwell_s`` or longer is a dwell, not part of a sweep.

    Rows left out of the sweeps (warm-up, load ramps and other transitions, short holds,
    free rolling, dwells, turning points) stay in the table with ``keep_dropped=True``
    (default) as rows with ``fit_row`` False and their ``drop_reason``, in time order
    with the sweep rows: a fit ignores them (:func:`mftire.iotools.sweeps.fit_rows`), the
    diagnosis may use them (a thermal effect shows most in the warm-up).  With
    ``points_per_sweep`` they are binned too, into bins of as many raw rows as a sweep
    point has on average.  Rows with a non-finite input or Fz <= 0 are not kept.

    Returns
    -------
    (DataFrame, RigReport)
        The sweep table (schema columns, extra channels, sweep labels, ``row_first``,
        ``row_last``, ``fit_row`` (bool), ``drop_reason`` ("" on sweep rows)) and the
        report.  Left-out rows have ``sweep_id`` -1, ``sweep_dir`` 0, ``kind``,
        ``sweep_var`` and ``direction`` ``"none"``, the set points of their segment (NaN
        between segments) and NaN ``kappa_set``/``alpha_set``.
    """
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        raise MftireInputError(f"segment: missing column(s) {', '.join(missing)}")
    n = len(df)
    if n < 3:
        raise MftireInputError(f"segment: {n} rows; a time series needs more")
    tcol = time or df.attrs.get("time_column")
    t = df[tcol].to_numpy(float) if tcol else np.arange(n, dtype=float)
    dts = np.diff(t)
    dt = float(np.median(dts[dts > 0])) if np.any(dts > 0) else 1.0
    fs = 1.0 / dt
    w_smooth = max(3, int(round(smooth_s * fs)) | 1)
    w_hold = max(3, int(round(hold_s * fs)) | 1)
    tols = condition_tolerances(fz_tol, gamma_tol, p_tol, vx_tol, vx_abs_tol)
    rep = RigReport(file=name or str(df.attrs.get("file", "")), n_rows=n, duration_s=float(t[-1] - t[0]),
                    sample_rate_hz=fs, convention=str(df.attrs.get("convention", "")),
                    units_read=dict(df.attrs.get("units_read", {})),
                    channel_map=dict(df.attrs.get("channel_map", {})),
                    messages=list(df.attrs.get("messages", [])))  # fmt: skip

    # 1-2: steady rows and levels of every condition
    labels = np.zeros((n, len(_CONDITIONS)), dtype=np.int64)
    first_bad = np.full(n, -1, dtype=int)  # index of the first condition not at a level
    level_values: dict[str, np.ndarray] = {}
    for j, c in enumerate(_CONDITIONS):
        x = df[c].to_numpy(float)
        sm = pd.Series(x).rolling(w_smooth, center=True, min_periods=1).mean()
        move = (sm.rolling(w_hold, center=True, min_periods=1).max()
                - sm.rolling(w_hold, center=True, min_periods=1).min()).to_numpy()  # fmt: skip
        s = sm.to_numpy()
        steady = move <= _tol(c, s, tols)
        rel, ab = tols[c]
        lab = np.full(n, -1, dtype=np.int64)
        if steady.any():
            cl = cluster_1d(s[steady], rel_tol=rel, abs_tol=ab)
            ids, counts = np.unique(cl, return_counts=True)
            big = ids[counts >= max(1, int(min_segment_s * fs * 0.5))]
            kind = _SET_POINT_KIND[c]
            centres = np.array([set_point(s[steady][cl == i], kind) for i in big])
            if centres.size:
                order = np.argsort(centres)
                centres = centres[order]
                near = np.abs(s[:, None] - centres[None, :])
                k = np.argmin(near, axis=1)
                ok = steady & (near[np.arange(n), k] <= _tol(c, centres[k], tols))
                lab[ok] = k[ok]
            level_values[c] = centres
        else:
            level_values[c] = np.array([])
        labels[:, j] = lab
        first_bad[(lab < 0) & (first_bad < 0)] = j
    rep.levels = {c: [float(v) for v in level_values[c]] for c in _CONDITIONS}

    # 3: segments = runs of one level of every condition
    in_cond = first_bad < 0
    code = np.where(in_cond, labels @ (np.int64(1000) ** np.arange(len(_CONDITIONS))), -1)
    run = _runs(code)
    reason = np.empty(n, dtype=object)
    reason[:] = ""
    not_in = ~in_cond
    for j, c in enumerate(_CONDITIONS):
        reason[not_in & (first_bad == j)] = f"{_REASON_NAMES[c]} (transition between levels)"
    run_start = np.flatnonzero(np.r_[True, run[1:] != run[:-1]])
    run_end = np.r_[run_start[1:], n]
    seg_rows: list[tuple[int, int, int]] = []  # (start, end, code) of candidate segments
    for s0, e0 in zip(run_start, run_end, strict=True):
        if code[s0] < 0:
            continue
        seg_rows.append((int(s0), int(e0), int(code[s0])))
    keep = np.zeros(n, dtype=bool)
    seg_id = np.full(n, -1, dtype=int)
    alpha = df["alpha"].to_numpy(float)
    kappa = df["kappa"].to_numpy(float)
    warm_end_t = None
    if isinstance(warmup, (int, float)) and not isinstance(warmup, bool) and warmup > 0:
        warm_end_t = t[0] + float(warmup)
    elif warmup not in (None, "auto", 0, False, "none", "off"):
        raise MftireInputError(f"warmup must be 'auto', 'none' or a number of seconds, got {warmup!r}")
    auto_warm = warmup == "auto"
    first_long = True
    seg_all = np.full(n, -1, dtype=int)  # segment of every row, kept or dropped (-1: between segments)
    for k_seg, (s0, e0, cd) in enumerate(seg_rows):
        seg_all[s0:e0] = k_seg
        entry: dict[str, Any] = {"row_first": s0, "row_last": e0 - 1, "t_start": float(t[s0]),
                                 "t_end": float(t[e0 - 1]), "n_rows": e0 - s0}  # fmt: skip
        for j, c in enumerate(_CONDITIONS):
            entry[c] = float(level_values[c][labels[s0, j]])
        dur = float(t[e0 - 1] - t[s0])
        why = ""
        if dur < min_segment_s:
            why = f"short hold ({dur:.1f} s < {min_segment_s:g} s)"
        elif warm_end_t is not None and t[e0 - 1] <= warm_end_t:
            why = f"warm-up (first {warmup:g} s)"
        elif auto_warm and first_long and any(c2 == cd for (_, _, c2) in seg_rows[k_seg + 1:]):
            why = "warm-up (first segment; its condition is measured again later)"
        first_long = first_long and dur < min_segment_s
        if not why:
            a_rng = float(np.subtract(*np.percentile(alpha[s0:e0], [98, 2])))
            k_rng = float(np.subtract(*np.percentile(kappa[s0:e0], [98, 2])))
            if a_rng <= 2 * alpha_tol and k_rng <= 2 * kappa_tol:
                why = "no slip sweep (free rolling or a held slip)"
        if why:
            entry.update(status="dropped", reason=why)
            reason[s0:e0] = why
        else:
            entry.update(status="kept", reason="")
            keep[s0:e0] = True
            seg_id[s0:e0] = k_seg
            if warm_end_t is not None and t[s0] < warm_end_t:
                part = t[s0:e0] < warm_end_t
                keep[s0:e0][part] = False
                reason[s0:e0][part] = f"warm-up (first {warmup:g} s)"
        rep.segments.append(entry)

    # 5: sweeps inside the kept segments, split at turning points of the swept slip
    sweep = np.full(n, -1, dtype=np.int64)
    sdir = np.zeros(n, dtype=int)
    seg_info: dict[int, dict[str, Any]] = {}
    w_dir = max(3, int(round(0.05 * fs)) | 1)
    lag = max(1, int(round(0.05 * fs)))
    min_dwell = max(min_sweep_points, int(round(min_dwell_s * fs)))
    next_id = 0
    for k_seg, entry in enumerate(rep.segments):
        if entry["status"] != "kept":
            continue
        s0, e0 = entry["row_first"], entry["row_last"] + 1
        rows = np.arange(s0, e0)[keep[s0:e0]]
        if rows.size < min_sweep_points:
            continue
        a, kp = alpha[rows], kappa[rows]
        kind = sweep_kind(kp, a, kappa_tol=kappa_tol, alpha_tol=alpha_tol)
        ra = float(np.subtract(*np.percentile(a, [98, 2]))) / alpha_tol
        rk = float(np.subtract(*np.percentile(kp, [98, 2]))) / kappa_tol
        var = "alpha" if ra >= rk else "kappa"
        x = a if var == "alpha" else kp
        tol = alpha_tol if var == "alpha" else kappa_tol
        # direction from the change of the smoothed slip over +-lag; "moving" beyond a dead band
        xs = pd.Series(x).rolling(w_dir, center=True, min_periods=1).mean().to_numpy()
        xp = np.pad(xs, lag, mode="edge")
        d = xp[2 * lag:] - xp[: -2 * lag]
        moving = np.abs(d) > 0.1 * tol
        still = _runs(moving)
        dwell = ~moving & (np.bincount(still)[still] >= min_dwell)  # the slip is held: not a sweep
        sg = np.where(moving, np.sign(d), np.nan)
        sg = pd.Series(sg).ffill().bfill().fillna(1.0).to_numpy(copy=True)
        sg[dwell] = 0.0
        r = _runs(sg)
        # short flickers near turning points: take the direction of the run before them
        cnt = np.bincount(r)
        short = (cnt[r] < min_sweep_points) & ~dwell
        if short.any() and not short.all():
            sg2 = sg.copy()
            sg2[short] = np.nan
            sg = pd.Series(sg2).ffill().bfill().to_numpy()
            r = _runs(sg)
        gx = pd.Series(x).groupby(r)
        span = (gx.max() - gx.min()).to_numpy()
        cnt = np.bincount(r)
        good = (span[r] > 2 * tol) & (cnt[r] >= min_sweep_points) & (sg != 0)
        keep[rows[dwell]] = False
        reason[rows[dwell]] = "dwell (slip held, no sweep)"
        drop_rows = rows[~good & ~dwell]
        keep[drop_rows] = False
        reason[drop_rows] = "turning point (sweep shorter than the minimum)"
        _, ids = np.unique(r[good], return_inverse=True)
        sweep[rows[good]] = ids + next_id
        sdir[rows[good]] = sg[good].astype(int)
        seg_info[k_seg] = {"kind": kind, "sweep_var": var,
                           "alpha_set": np.nan if var == "alpha" else float(np.median(a)),
                           "kappa_set": np.nan if var == "kappa" else float(np.median(kp))}  # fmt: skip
        next_id += int(ids.max()) + 1 if ids.size else 0

    kept_rows = np.flatnonzero(keep)
    for why, cnt in pd.Series(reason[~keep]).value_counts().items():
        rep.dropped[str(why) or "other"] = int(cnt)
    rep.rows_kept = int(kept_rows.size)
    if kept_rows.size == 0:
        raise MftireInputError(f"{rep.file}: no sweep found in the time series\n{rep}")

    # output table: the kept rows, with labels
    base = df.iloc[kept_rows].reset_index(drop=True)
    base["row_first"] = kept_rows
    base["row_last"] = kept_rows
    base["sweep_id"] = sweep[kept_rows]
    base["sweep_dir"] = sdir[kept_rows]
    segs = seg_id[kept_rows]
    base["_seg"] = segs
    if points_per_sweep:
        if int(points_per_sweep) < 1:
            raise MftireInputError(f"points per sweep must be >= 1, got {points_per_sweep}")
        npts = int(points_per_sweep)
        pos = base.groupby("sweep_id", sort=False).cumcount().to_numpy()
        size = base.groupby("sweep_id", sort=False)["sweep_id"].transform("size").to_numpy()
        base["_bin"] = (pos * npts) // size
        keys = ["sweep_id", "_bin"]
        num = [c for c in base.columns if c not in keys and pd.api.types.is_numeric_dtype(base[c])]
        other = [c for c in base.columns if c not in keys and c not in num]
        g = base.groupby(keys, sort=True)
        agg = g[num].mean()
        agg["row_first"] = g["row_first"].min()
        agg["row_last"] = g["row_last"].max()
        agg["sweep_dir"] = g["sweep_dir"].first()
        agg["_seg"] = g["_seg"].first()
        if other:
            agg = agg.join(g[other].first())
        base = agg.reset_index().drop(columns="_bin").sort_values("row_first", kind="stable")
        base = base.reset_index(drop=True)
    segs = base["_seg"].to_numpy()
    for c in _CONDITIONS:
        lv = np.array([rep.segments[s][c] for s in range(len(rep.segments))])
        base[SET_POINT_COLUMNS[c]] = lv[segs]
    for key in ("kind", "sweep_var", "kappa_set", "alpha_set"):
        m = {s: info[key] for s, info in seg_info.items()}
        base[key] = pd.Series(segs).map(m).to_numpy()
    base["direction"] = np.where(base["sweep_dir"].to_numpy() > 0, "increasing", "decreasing")
    base = base.drop(columns="_seg")
    first = base.groupby("sweep_id", sort=False)["direction"].first()
    rep.n_sweeps = int(first.size)
    rep.directions = {str(k): int(v) for k, v in first.value_counts().items()}
    rep.n_points = len(base)
    base["fit_row"] = True
    base["drop_reason"] = ""
    if keep_dropped:
        rows_per_point = max(1, int(round(kept_rows.size / max(len(base), 1))))
        left = _left_out_rows(df, keep, reason, seg_all, rep, rows_per_point if points_per_sweep else 1)
        if len(left):
            base = pd.concat([base, left], ignore_index=True, sort=False)
            base = base.sort_values("row_first", kind="stable").reset_index(drop=True)
    # no attrs on the table: pandas deep-copies them on every column access, which slows every
    # later step (fit, diagnosis); the report holds what they held
    base.attrs = {}
    return base, rep


def _left_out_rows(df: pd.DataFrame, keep: np.ndarray, reason: np.ndarray, seg_all: np.ndarray, rep: RigReport,
                   rows_per_point: int) -> pd.DataFrame:
    """The rows :func:`segment` leaves out of the sweeps, labelled, as ``fit_row`` False rows.

    Contiguous rows with one reason are averaged in bins of ``rows_per_point`` rows (1:
    every row), in time order.
    """
    inputs = df[list(REQUIRED_COLUMNS)].to_numpy(float)
    ok = ~keep & np.isfinite(inputs).all(axis=1) & (df["Fz"].to_numpy(float) > 0)
    rows = np.flatnonzero(ok)
    if rows.size == 0:
        return pd.DataFrame()
    why = reason[rows].astype(str)
    new_run = np.r_[True, (np.diff(rows) > 1) | (why[1:] != why[:-1])]
    run = np.cumsum(new_run) - 1
    pos = np.arange(rows.size) - np.flatnonzero(new_run)[run]
    part = df.iloc[rows].reset_index(drop=True)
    part["row_first"] = rows
    part["row_last"] = rows
    part["_seg"] = seg_all[rows]
    part["drop_reason"] = np.where(why == "", "other", why)
    if rows_per_point > 1:
        part["_bin"] = run * (rows.size + 1) + pos // rows_per_point
        num = [c for c in part.columns if c not in ("_bin", "_seg", "row_first", "row_last")
               and pd.api.types.is_numeric_dtype(part[c])]
        other = [c for c in part.columns if c not in num and c not in ("_bin", "row_first", "row_last")]
        g = part.groupby("_bin", sort=True)
        agg = g[num].mean()
        agg["row_first"] = g["row_first"].min()
        agg["row_last"] = g["row_last"].max()
        agg = agg.join(g[other].first())
        part = agg.reset_index(drop=True)
    segs = part["_seg"].to_numpy()
    for c in _CONDITIONS:
        lv = np.array([np.nan] + [entry[c] for entry in rep.segments], dtype=float)
        part[SET_POINT_COLUMNS[c]] = lv[segs + 1]
    part["sweep_id"] = -1
    part["sweep_dir"] = 0
    part["kind"] = part["sweep_var"] = part["direction"] = "none"
    part["kappa_set"] = part["alpha_set"] = np.nan
    part["fit_row"] = False
    return part.drop(columns="_seg")


def import_rig(
    path: PathLike,
    fmt: str = "ttc",
    *,
    output: PathLike | None = None,
    columns: Mapping[str, ColumnSpec | str | Mapping] | None = None,
    column_map: PathLike | None = None,
    convention: str | None = None,
    signs: Mapping[str, float] | None = None,
    points_per_sweep: int | None = None,
    **segment_kw: Any,
) -> tuple[pd.DataFrame, RigReport]:
    """Read a raw rig file, convert it to SI/ISO, segment it and (with ``output``) write the sweep CSV.

    ``fmt`` is ``"ttc"`` or ``"columns"``; for ``"columns"`` the column map comes from
    ``column_map`` (TOML, :func:`read_column_map`) and/or ``columns`` (which win).
    ``convention`` defaults to SAE for TTC files and to the map's (else ISO) for columns.
    Other keywords go to :func:`segment`.
    """
    t0 = _time.perf_counter()
    p = os.fspath(path)
    df = read_raw(p, fmt, columns=columns, column_map=column_map, convention=convention, signs=signs)
    table, rep = segment(df, points_per_sweep=points_per_sweep, name=p, **segment_kw)
    rep.seconds = _time.perf_counter() - t0
    if output is not None:
        write_sweeps(table, output)
    return table, rep
