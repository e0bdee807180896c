"""Magic Formula models for comparison: loading and evaluation at data points and on grids.

Models are evaluated with :meth:`mftire.tyre.Tyre.evaluate` (default mode 111, the
standard evaluation with the ``.tir``'s input limits) at

* the *exact operating points* of every data row (measured Fz, κ, α, γ, Vx, P, φt), so
  model and data are comparable point by point (:func:`evaluate_at`), and
* the smooth grids of :func:`mftire.compare.data.curve_grid` for plotting.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence

import pandas as pd

from mftire.errors import MftireInputError
from mftire.tyre import Tyre, as_tyre

__all__ = ["MODEL_CHANNELS", "load_models", "evaluate_at", "evaluate_models"]

#: Channels kept from the evaluator: forces [N], moments [N·m], pneumatic trail t [m],
#: residual torque Mzr [N·m], cornering stiffness Kya [N/rad], slip stiffness Kxk [N].
MODEL_CHANNELS: tuple[str, ...] = ("Fx", "Fy", "Mz", "Mx", "My", "t", "Mzr", "Kya", "Kxk")


def load_models(models: Iterable[str | os.PathLike | Tyre] | Mapping[str, str | os.PathLike | Tyre]) -> dict:
    """``{name: Tyre}`` from ``.tir`` paths or :class:`Tyre` objects.

    Names are the file stems (or given keys); duplicates get ``#2``, ``#3`` ... suffixes.
    """
    items = list(models.items()) if isinstance(models, Mapping) else [(None, m) for m in models]
    out: dict[str, Tyre] = {}
    for name, m in items:
        tyre = as_tyre(m)
        base = name or (os.path.splitext(tyre.name)[0] if not isinstance(m, Tyre) else tyre.name)
        label, i = str(base), 2
        while label in out:
            label, i = f"{base}#{i}", i + 1
        out[label] = tyre
    if not out:
        raise MftireInputError("no model: give at least one .tir (--tir)")
    return out


def evaluate_at(
    tyre: Tyre, points: pd.DataFrame, mode: int = 111, channels: Sequence[str] = MODEL_CHANNELS
) -> pd.DataFrame:
    """Model channels at the operating points of ``points``.

    Parameters
    ----------
    tyre : Tyre
    points : DataFrame
        Columns ``Fz`` [N], ``kappa`` [-], ``alpha`` [rad], ``gamma`` [rad], ``Vx``
        [m/s], ``P`` [Pa] and optionally ``phit`` [1/m] plus the variables the model's
        extensions need (e.g. ``temperature``).
    mode : int
        Evaluation mode (MFeval ``useMode``, default 111).
    channels : sequence of str
        Output channels to keep.

    Returns
    -------
    DataFrame
        Same index as ``points``, one column per channel (SI).
    """
    if len(points) == 0:
        return pd.DataFrame(columns=list(channels), index=points.index, dtype=float)
    return tyre.evaluate_frame(points.drop(columns=["omega"], errors="ignore"), mode=mode,
                               name=f"data for model {tyre.name}")[list(channels)]


def evaluate_models(models: Mapping[str, Tyre], points: pd.DataFrame, mode: int = 111) -> dict[str, pd.DataFrame]:
    """:func:`evaluate_at` for every model: ``{name: DataFrame}``."""
    return {name: evaluate_at(t, points, mode) for name, t in models.items()}
