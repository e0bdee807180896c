"""Data preparation for fitting: weights and noise estimates.

The sweep table itself (schema, validation, grouping) lives in
:mod:`mftire.iotools.sweeps`, the shared loaders (:func:`load_sweep_files`,
:func:`prepare_table`, :func:`check_columns`) in :mod:`mftire.iotools.loaders`
(re-exported here); this module adds what fitting needs on top of them:

* :func:`parse_weights` / :func:`row_weights` turn ``"fe=1,measured=5"`` into per-row
  weights keyed on ``source`` (or file name);
* :func:`noise_std` estimates the measurement noise of a channel from second
  differences along each sweep (robust, MAD based).
"""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np
import pandas as pd
from scipy import stats

from mftire.errors import MftireInputError
from mftire.iotools.loaders import check_columns, load_sweep_files, prepare_table

__all__ = [
    "check_columns",
    "load_sweep_files",
    "prepare_table",
    "parse_weights",
    "row_weights",
    "noise_std",
]


def parse_weights(spec: str | Mapping[str, float] | None) -> dict[str, float]:
    """``"fe=1,measured=5"`` -> ``{"fe": 1.0, "measured": 5.0}``.

    Raises
    ------
    MftireInputError
        On a malformed item or a negative / non-finite weight.
    """
    if spec is None or spec == "":
        return {}
    if isinstance(spec, Mapping):
        items = list(spec.items())
    else:
        items = []
        for raw in str(spec).split(","):
            if not raw.strip():
                continue
            if "=" not in raw:
                raise MftireInputError(f"--weights: {raw.strip()!r} is not SOURCE=WEIGHT (e.g. fe=1,measured=5)")
            key, value = raw.split("=", 1)
            items.append((key.strip(), value.strip()))
    out: dict[str, float] = {}
    for key, value in items:
        try:
            w = float(value)
        except (TypeError, ValueError):
            raise MftireInputError(f"--weights: weight of {key!r} is not a number: {value!r}") from None
        if not np.isfinite(w) or w < 0:
            raise MftireInputError(f"--weights: weight of {key!r} must be a finite number >= 0, got {value!r}")
        out[str(key)] = w
    return out


def row_weights(df: pd.DataFrame, weights: Mapping[str, float]) -> np.ndarray:
    """Per-row weight from ``{source or file name: weight}`` (1 where not listed).

    A key matches the ``source`` column, or the ``file`` column by base name or stem.

    Raises
    ------
    MftireInputError
        When a key matches no row (the message lists the available sources).
    """
    w = np.ones(len(df))
    if not weights:
        return w
    src = df["source"].astype(str).to_numpy() if "source" in df.columns else np.full(len(df), "")
    files = df["file"].astype(str).to_numpy() if "file" in df.columns else np.full(len(df), "")
    base = np.array([os.path.basename(f) for f in files])
    stem = np.array([os.path.splitext(b)[0] for b in base])
    for key, value in weights.items():
        hit = (src == key) | (files == key) | (base == key) | (stem == key)
        if not hit.any():
            avail = sorted(set(src) | set(base))
            raise MftireInputError(f"--weights: no data with source or file {key!r}; available: {', '.join(avail)}")
        w[hit] = value
    return w


def noise_std(y: np.ndarray, x: np.ndarray, groups: np.ndarray | None = None) -> float:
    """Robust noise standard deviation of ``y`` measured along ``x`` [unit of y].

    Within each group (sweep) points are sorted by ``x`` and the second differences
    ``y[i-1] - 2 y[i] + y[i+1]`` (variance 6σ² for white noise) are formed; σ is the
    normalised median absolute deviation of all of them divided by √6.  A smooth curve
    contributes little to second differences, gross outliers nothing (median).
    """
    y = np.asarray(y, dtype=float)
    x = np.asarray(x, dtype=float)
    if groups is None:
        groups = np.zeros(y.size, dtype=int)
    d2: list[np.ndarray] = []
    for g in np.unique(groups):
        m = groups == g
        if m.sum() < 3:
            continue
        order = np.argsort(x[m], kind="stable")
        yy = y[m][order]
        d2.append(yy[:-2] - 2.0 * yy[1:-1] + yy[2:])
    if not d2:
        return 0.0
    d = np.concatenate(d2)
    d = d[np.isfinite(d)]
    if d.size == 0:
        return 0.0
    return float(stats.median_abs_deviation(d, scale="normal") / np.sqrt(6.0))
