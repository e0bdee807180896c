"""Issue 21: the random effect zoo (validation/effect_zoo.py), its generator and the judge on 16 draws.

The generator is checked with real numbers (reproducible from the seed, a quarter nulls, the ground
truth and identifier columns present, the effect visible above the noise, the held-out design keeps
the MF conditions); the current diagnosis is judged on 16 fixed draws (seeds 0-15: 12 effect draws
and 4 nulls, two processes): no scored channel more than 5 % worse on held-out data, no finding on the
nulls, an oracle ceiling for every effect draw, and the cause and cut rates no lower than measured.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location("effect_zoo", ROOT / "validation" / "effect_zoo.py")
zoo = importlib.util.module_from_spec(_spec)
sys.modules["effect_zoo"] = zoo
_spec.loader.exec_module(zoo)

N_EFFECT, N_NULL = 12, 4


#: the draws CI judges: the first 16 seeds (12 effect draws and 4 nulls: one null in every four seeds), the
#: slowest first (as measured at commit time), so that the two processes finish together
CI_SEEDS = (4, 10, 15, 2, 7, 14, 0, 8, 6, 3, 13, 12, 11, 1, 9, 5)


def test_ci_judges_the_first_16_seeds():
    assert sorted(CI_SEEDS) == list(range(16))


@pytest.fixture(scope="module")
def truths() -> list[dict]:
    return [zoo.draw(s).truth for s in range(100)]


def test_draw_is_reproducible_from_its_seed():
    a, b, c = zoo.draw(7), zoo.draw(7), zoo.draw(8)
    pd.testing.assert_frame_equal(a.data, b.data)
    assert np.array_equal(a.holdout, b.holdout) and a.truth == b.truth
    assert not a.data.shape == c.data.shape or not np.allclose(a.data.Fy, c.data.Fy)


def test_a_quarter_of_the_draws_are_nulls(truths):
    nulls = np.array([t["is_null"] for t in truths])
    assert nulls.mean() == zoo.NULL_FRACTION  # one in each block of four consecutive seeds
    assert nulls.reshape(-1, 4).sum(axis=1).tolist() == [1] * 25
    assert len({int(np.argmax(b)) for b in nulls.reshape(-1, 4)}) == 4  # not always the same position
    kinds = {t["null_kind"] for t in truths if t["is_null"]}
    assert kinds == set(zoo.NULL_KINDS)


def test_the_zoo_spans_the_issue_list(truths):
    eff = [t for t in truths if not t["is_null"]]
    assert {t["family"] for t in eff} == set(zoo.FAMILIES)
    assert {t["shape"] for t in eff} >= set(zoo.SHAPES) | {"step", "direction"}
    assert {t["variable_kind"] for t in eff} == set(zoo.VARIABLE_KINDS)
    assert {t["interaction"] for t in eff} >= set(zoo.INTERACTIONS)
    designs = {t["holdout_design"].split(" ")[0] for t in truths}
    assert designs == {"new_runs", "interior_load", "unseen_level", "unseen_combination"}
    assert any("follows friction power" in t["confounding"] for t in eff)
    assert any(t["not_measured"] for t in truths)
    # the effect shows above the noise on its channel in almost every effect draw
    snr = np.array([t["snr"] for t in eff])
    assert np.mean(snr >= 1.5) >= 0.9, np.sort(snr)[:10]


@pytest.mark.parametrize("seed", range(0, 60, 2))
def test_ground_truth_and_identifier_columns_present(seed):
    d = zoo.draw(seed)
    t = d.truth
    for key in ("is_null", "family", "targets", "shape", "variable", "accepted", "size", "confounding",
                "holdout_design", "identifiers", "law_expressible"):  # fmt: skip
        assert key in t
    for col in t["identifiers"].values():  # run, sweep, segment, row, file numbers
        assert col in d.data.columns and pd.api.types.is_integer_dtype(d.data[col])
    assert d.data[t["identifiers"]["row"]].is_unique
    assert "time" in d.data.columns and np.all(np.diff(d.data.time) >= 0)
    for col in t["decoys"]:
        assert col in d.data.columns
    if t["is_null"]:
        assert t["variable"] is None and (d.law_g is None) == (t["null_kind"] != "run_scatter")
    else:
        assert t["variable"] in t["accepted"] and len(t["targets"]) >= 1
        if t["variable_kind"] not in ("mf_input", "direction"):
            assert t["variable"] in d.data.columns  # the generating column is in the data
        assert t["snr"] > 0 and np.isfinite(t["size"]) and t["size"] != 0
    # held out: whole runs, some, never all; training keeps braking and cornering sweeps
    run = d.data[t["identifiers"]["run"]]
    assert 0 < d.holdout.sum() < len(d.holdout)
    assert not (set(run[d.holdout]) & set(run[~d.holdout]))
    tr = d.train
    assert (tr.kappa.abs() > 0.05).any() and (tr.alpha.abs() > 0.05).any()
    # every MF operating condition of the held-out runs is also in training (unless a load is held out)
    loads = np.array(t["levels"]["loads"])
    per_run = d.data.groupby(run).agg(Fz=("Fz", "mean"), gamma=("gamma", "first"), Vx=("Vx", "first"),
                                      P=("P", "first"))  # fmt: skip
    per_run["load"] = loads[np.argmin(np.abs(per_run.Fz.to_numpy()[:, None] - loads[None, :]), axis=1)]
    cond = per_run[["load", "gamma", "Vx", "P"]].round(6).apply(tuple, axis=1)
    held_runs = set(run[d.holdout])
    held, trained = {cond[r] for r in held_runs}, {cond[r] for r in cond.index if r not in held_runs}
    if t["holdout_design"] == "interior_load":
        assert len({c[0] for c in held}) == 1 and not {c[0] for c in held} & {c[0] for c in trained}
        assert len({c[0] for c in trained}) >= 3  # the load terms stay identifiable
    else:
        assert held <= trained, held - trained


@pytest.fixture(scope="module")
def judged() -> pd.DataFrame:
    # the draws are independent: two processes on CI's two cores (forked, so the zoo module is theirs too)
    import functools
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork")) as pool:
        return pd.DataFrame(list(pool.map(functools.partial(zoo.evaluate_draw, n_perm=49), CI_SEEDS)))


def test_ceiling_computed_for_every_effect_draw(judged):
    eff = judged[~judged.is_null]
    assert len(eff) == N_EFFECT and judged.is_null.sum() == N_NULL
    assert np.isfinite(eff.ceiling_cut).all(), eff[["seed", "ceiling_cut"]]
    # the refit with the generating law is never far worse than the plain fit, and reaches a real cut
    assert (eff.ceiling_cut > -0.1).all() and (eff.ceiling_cut >= 0.5).sum() >= 3, eff.ceiling_cut.tolist()


def test_no_false_finding_on_the_nulls(judged):
    nul = judged[judged.is_null]
    assert not nul.finding.any(), nul[["seed", "null_kind", "found_first", "law"]]


#: Issue 21's hard rule: no scored channel's held-out error more than 5 % worse than the model as given.
def test_no_scored_channel_worse_than_5_percent_held_out(judged):
    bad = judged[judged.violation]
    assert bad.empty, bad[["seed", "family", "law", "worst_change"]].to_string()


#: What the diagnosis reaches on the 16 CI draws: at b2dde38 11 of 12 causes named first and 4 of the 8 draws with a
#: ceiling >= 70 % cut by >= 50 %; since d1a8189 (2026-11-27) 11 of 12 and 3 of 8.  The bounds are the numbers of
#: b2dde38 less one draw each, so that a regression fails here.
def test_cause_and_cut_rates_do_not_regress(judged):
    eff = judged[~judged.is_null]
    assert eff.cause_named.sum() >= 10, eff[["seed", "family", "variable", "cause"]].to_string()
    ceil = eff[eff.ceiling_cut >= zoo.CEILING_MIN]
    assert (ceil.cut >= zoo.CUT_MIN).sum() >= 3, ceil[["seed", "family", "law", "cut", "ceiling_cut"]].to_string()


def test_headline_rates_are_the_issue_definitions():
    df = pd.DataFrame({"is_null": [False, False, False, True, True], "cause_named": [True, False, True, False, False],
                       "ceiling_cut": [0.8, 0.9, 0.3, math.nan, math.nan], "cut": [0.6, 0.2, 0.0, 0.0, 0.0],
                       "violation": [False, True, False, False, False], "finding": [True, True, False, True, False]})
    h = zoo.headline(df)
    assert h["cause_named_first"] == pytest.approx(2 / 3)
    assert h["ceiling_draws"] == 2 and h["cut_ge_50_where_ceiling_ge_70"] == 0.5
    assert h["violations"] == 1 and h["false_findings_on_nulls"] == 0.5


def test_the_judge_flags_a_channel_made_worse_and_scores_the_cut():
    d = zoo.draw(2)
    held = d.data[d.holdout & ~d.outlier]
    truth = d.clean[d.holdout & ~d.outlier]
    before = truth.copy()
    before["Fy"] = truth["Fy"] + 0.05 * float(truth["Fy"].abs().max())  # the base model misses an Fy offset
    chans = ["Fx", "Fy", "Mz"]
    same = zoo.score_heldout(held, before, before, truth, truth, chans)
    assert same["cut"] == 0.0 and same["worst_change"] == 0.0 and not same["violation"]
    assert same["ceiling_cut"] > 0.5 and same["best_cut"] == same["ceiling_cut"]
    fixed = zoo.score_heldout(held, before, truth, truth, None, chans)
    assert fixed["cut"] > 0.5 and not fixed["violation"] and math.isnan(fixed["ceiling_cut"])
    worse = truth.copy()
    worse["Fx"] = truth["Fx"] * 1.03  # Fx made 3 % of its value worse: many noise sigmas
    bad = zoo.score_heldout(held, truth, worse, truth, None, chans)
    assert bad["violation"] and bad["change_Fx"] > 0.05 and bad["change_Fy"] == 0.0
    assert zoo.score_heldout(held, truth, None, truth, None, chans)["violation"]  # not evaluable: a violation


def test_aliased_r2_says_when_the_training_rows_cannot_tell_the_effect_from_the_set_points():
    # seed 89: a heater flag on in the 9.8 kN runs only, off in every other training run: constant in every cell
    assert zoo.aliased_r2(zoo.draw(89)) == pytest.approx(1.0)
    assert zoo.aliased_r2(zoo.draw(0)) < 0.5  # a wear drift across the runs of every load
    assert math.isnan(zoo.aliased_r2(zoo.draw(8)))  # a law in Vx, an MF input (a set point itself)
    assert math.isnan(zoo.aliased_r2(zoo.draw(1)))  # a null
    # the table's breakdown, from the shipped results (an old file without the column: computed from the draws)
    df = pd.read_csv(ROOT / "validation" / "effect_zoo_results.csv")
    df = df[df.seed.isin([88, 89])].drop(columns=["aliased_r2"], errors="ignore")
    text = zoo.table_markdown(df, "x")
    assert f"| aliased with the set points (R² ≥ {zoo.ALIASED_R2}) | 1 | 0 % | 1 | 0 % | 0 |" in text
    assert "| the others | 1 |" in text
