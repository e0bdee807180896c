"""Sweep grouping against sweeps whose boundaries are known, in the orders rigs and the FE write them.

Every table here is built sweep by sweep, so the true first row of every sweep is known;
:func:`group_sweeps` must find exactly those boundaries (issue 26.1: the first points
|kappa| <= 0.0067 of an alpha = 0 braking sweep written after a cornering sweep at the
same conditions used to be grouped into the cornering sweep).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.fe.slip_sweeps import alpha_grid, kappa_grid
from mftire.segmentation.grouping import group_sweeps

DEG = math.pi / 180


def _sweep(kappa, alpha, fz: float = 4000.0, vx: float = 60 / 3.6) -> pd.DataFrame:
    kappa, alpha = np.broadcast_arrays(np.asarray(kappa, float), np.asarray(alpha, float))
    return pd.DataFrame({"Fz": fz, "kappa": kappa, "alpha": alpha, "gamma": 0.0, "Vx": vx, "P": 2.2e5})


# the sweeps of the catalogue: (kappa, alpha) as the FE (kappa_grid, alpha_grid) and rigs write them
def braking(n: int = 14) -> pd.DataFrame:
    return _sweep(kappa_grid(n), 0.0)  # 0, -0.0059, -0.024, ... -1 (FE spacing)


def driving(n: int = 12) -> pd.DataFrame:
    return _sweep(np.linspace(0.0, 0.4, n), 0.0)


def cornering(n: int = 17) -> pd.DataFrame:
    return _sweep(0.0, alpha_grid(n))  # -12 .. 12 deg


def cornering_from_zero(n: int = 13) -> pd.DataFrame:
    return _sweep(0.0, np.linspace(0.0, 12.0, n) * DEG)  # first point at exactly zero slip


def cornering_up_down(n: int = 9) -> pd.DataFrame:  # 0 -> 12 -> -12 -> 0 deg: direction changes
    up = np.linspace(0, 12, n)
    return _sweep(0.0, np.r_[up, up[::-1][1:], -up[1:], -up[::-1][1:]] * DEG)


def combined(alpha_deg: float, n: int = 14) -> pd.DataFrame:
    return _sweep(kappa_grid(n), alpha_deg * DEG)


def combined_alpha(kappa: float, n: int = 17) -> pd.DataFrame:
    return _sweep(kappa, alpha_grid(n))


def _table(sweeps: list[pd.DataFrame], noise: float = 0.0, seed: int = 0) -> tuple[pd.DataFrame, np.ndarray]:
    """The sweeps one after the other, and the index of each sweep's first row.

    ``noise`` > 0 makes it rig-like: the load wanders by +-2 %, a held slip by
    ``noise`` (kappa) and 0.05 deg (alpha), a swept one by a tenth of that.
    """
    table = pd.concat(sweeps, ignore_index=True)
    starts = np.cumsum([0, *[len(s) for s in sweeps[:-1]]])
    if noise:
        rng = np.random.default_rng(seed)
        n = len(table)
        table["Fz"] *= 1 + 0.02 * rng.standard_normal(n).clip(-2, 2)
        table["kappa"] += noise * rng.uniform(-1, 1, n)
        table["alpha"] += 0.05 * DEG * rng.uniform(-1, 1, n)
    return table, starts


def _found_starts(table: pd.DataFrame) -> np.ndarray:
    ids = group_sweeps(table)["sweep_id"].to_numpy()
    return np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]])


ORDERS = {
    # the FE's programme at one load: braking, cornering, then combined from alpha = 0 (issue 26.1)
    "fe_campaign": [braking(), cornering(), combined(0.0), combined(-5.0), combined(5.0)],
    "braking_after_cornering": [cornering(), braking()],
    "cornering_after_braking": [braking(), cornering()],
    "cornering_from_zero_after_braking": [braking(), cornering_from_zero()],
    "braking_after_cornering_from_zero": [cornering_from_zero(), braking()],
    "braking_after_direction_changes": [cornering_up_down(), braking(), cornering_up_down()],
    "repeated_braking": [braking(), braking(), braking()],
    "repeated_cornering": [cornering(), cornering()],
    "driving_after_braking": [braking(), driving(), braking()],
    "combined_alpha_after_cornering": [cornering(), combined_alpha(-0.05), combined_alpha(0.05)],
}


@pytest.mark.parametrize("noise", [0.0, 0.002], ids=["fe", "rig"])
@pytest.mark.parametrize("order", list(ORDERS))
def test_grouping_finds_known_boundaries(order, noise):
    table, starts = _table(ORDERS[order], noise=noise)
    np.testing.assert_array_equal(_found_starts(table), starts)


def test_braking_after_cornering_keeps_free_rolling_in_the_braking_sweep():
    # issue 26.1: the zero-slip point is the braking sweep's own, so Fx(kappa = 0) is read from it
    table, starts = _table([cornering(), braking()])
    g = group_sweeps(table)
    brake = g[g["sweep_id"] == g["sweep_id"].iloc[starts[1]]]
    assert len(brake) == 14 and brake["kappa"].iloc[0] == 0.0
    assert set(brake["kind"]) == {"pure_longitudinal"} and set(brake["sweep_var"]) == {"kappa"}
    corner = g[g["sweep_id"] == g["sweep_id"].iloc[0]]
    assert len(corner) == 17 and set(corner["kind"]) == {"pure_lateral"}


def test_direction_change_is_one_sweep_with_its_direction_word():
    table, _ = _table([cornering_up_down(), braking()])
    g = group_sweeps(table)
    first = g[g["sweep_id"] == 0]
    assert len(first) == 33 and first["direction"].iloc[0] == "mixed"
    assert g["sweep_id"].nunique() == 2


# a sweep may follow another of the same swept slip only where that slip jumps (else it is one sweep
# turning round, which no grouping can tell apart without a label)
_CATALOGUE = {"braking": braking, "driving": driving, "cornering": cornering, "cornering0": cornering_from_zero,
              "updown": cornering_up_down, "comb-5": lambda: combined(-5.0), "comb5": lambda: combined(5.0),
              "calpha": lambda: combined_alpha(-0.05)}  # fmt: skip
_CONTINUES = {("cornering0", "updown"), ("updown", "updown"), ("updown", "cornering0")}


@settings(max_examples=40, deadline=None)
@given(names=st.lists(st.sampled_from(sorted(_CATALOGUE)), min_size=2, max_size=6),
       noise=st.sampled_from([0.0, 0.001, 0.003]), seed=st.integers(0, 1000))
def test_grouping_property_any_order(names, noise, seed):
    kept = names[:1]
    for n in names[1:]:
        if (kept[-1], n) not in _CONTINUES:
            kept.append(n)
    names = kept
    table, starts = _table([_CATALOGUE[n]() for n in names], noise=noise, seed=seed)
    np.testing.assert_array_equal(_found_starts(table), starts, err_msg=" -> ".join(names))


def test_comparison_free_rolling_reads_each_braking_sweeps_own_zero_slip_point():
    # issue 26.1 end to end: the FE order braking, cornering, combined from alpha = 0 at one condition; Fx(kappa = 0)
    # of every braking curve in the comparison is the FE's own free-rolling value, not an extrapolation from -0.024
    from mftire.compare.data import prepare_comparison_data
    from mftire.compare.tables import free_rolling_table

    table, starts = _table(ORDERS["fe_campaign"])
    table["Fx"] = np.where(table["kappa"] == 0.0, -16.9, 5.0e4 * table["kappa"] - 16.9)  # Fx0 = -16.9 N
    free = free_rolling_table(prepare_comparison_data(table.assign(source="fe")), {})
    assert len(free) == 2  # the braking sweep and the combined sweep at alpha = 0
    np.testing.assert_allclose(free["Fx0_data"], -16.9, atol=1e-9)


def test_fine_sweep_ending_at_the_next_sweeps_level_keeps_its_points():
    # steps (0.1 deg) finer than the level tolerance (0.5 deg): the sweep's last points near alpha = 0 stay with it
    fine = _sweep(0.0, np.linspace(-12.0, 0.0, 121) * DEG)
    table, starts = _table([fine, braking()])
    np.testing.assert_array_equal(_found_starts(table), starts)
