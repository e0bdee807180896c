"""Issue 21: the diagnosis' laws hold on new data.

Identifiers are never candidates or law variables; a law acts on the channels it helps only; a law that
makes a channel worse on held-out data is never accepted ("cause named, no law found"); the aligning
moment's own targets (trail) are tried; the importer's flagged rows (``fit_row``) are used for the
accumulated candidates only.  Campaigns as in tests/test_diagnosis.py (a known MF tyre, one injected effect).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from test_diagnosis import TYRE, _campaign, _measure, _refit, _term

from mftire.diagnosis.candidates import candidates, is_identifier, numbers_things, with_sweeps
from mftire.diagnosis.diagnose import diagnose, split_fit_rows
from mftire.diagnosis.effects import CONTROL, EffectFit, Law, trimmed, worse_channels
from mftire.mf.extensions import SECTION

# the diagnosis evaluates held-out levels beyond a law's fitted range: clamped, with the range warning
pytestmark = pytest.mark.filterwarnings("ignore::mftire.mf.inputs.MFLimitWarning")


@pytest.fixture(scope="module")
def base_df():
    return _campaign()


def _with_identifiers(d: pd.DataFrame) -> pd.DataFrame:
    g = with_sweeps(d)
    out = d.copy()
    sweep = g["sweep_id"].factorize()[0]
    out["run"] = sweep  # named as one
    out["specimen"] = 100 + sweep  # only numbers things: integers spaced by one, one per sweep
    out["pt"] = np.arange(len(out))  # a row counter under an innocent name
    return out


def test_identifiers_are_never_candidates(base_df):
    d = with_sweeps(_with_identifiers(_measure(base_df, None)))
    names = {c.name for c in candidates(d)}
    assert not names & {"run", "specimen", "pt"}
    assert {"tread_temp", "time"} <= names
    sweeps = d["sweep_id"].to_numpy()
    assert numbers_things(d["specimen"].to_numpy(float), sweeps)
    assert numbers_things(d["pt"].to_numpy(float), sweeps)
    assert not numbers_things(d["tread_temp"].to_numpy(float), sweeps)
    assert not numbers_things(np.repeat([0.0, 1.0], len(d) // 2 + 1)[: len(d)], sweeps)  # a flag
    assert not is_identifier("time", np.arange(len(d), dtype=float), sweeps)  # a 1 Hz clock counts seconds


def test_worse_channels_and_trimmed_law():
    control = {"Fx": (1.0, 100), "Fy": (1.0, 100)}
    assert worse_channels({"Fx": (0.5, 100), "Fy": (1.01, 100)}, control) == []
    assert worse_channels({"Fx": (0.5, 100), "Fy": (1.03, 100)}, control) == ["Fy"]
    # within the noise: 2 % of the noise's sum of squares, never more than 2 % of the control's
    assert worse_channels({"Fx": (0.5, 100), "Fy": (1.03, 100)}, control, {"Fy": 0.25}) == []
    assert worse_channels({"Fx": (0.5, 100), "Fy": (1.05, 100)}, control, {"Fy": 10.0}) == ["Fy"]
    # a fold may lose by twice the allowance of the whole, no more
    folds = {"Fy": (1.0, 100), "Fy#0": (0.5, 50), "Fy#1": (0.5, 50)}
    assert worse_channels({"Fy": (1.0, 100), "Fy#0": (0.4, 50), "Fy#1": (0.6, 50)}, folds) == ["Fy"]
    # ... and by issue 21's 5 % in RMS (zoo seed 1010: a slip-angle offset 12x better than the control on the
    # held-out sweeps was refused for one fold of Fx, at its noise floor, 4 % worse in RMS)
    folds = {"Fx": (2.7, 238), "Fx#0": (0.3, 68), "Fx#2": (0.93, 68)}
    assert worse_channels({"Fx": (1.96, 238), "Fx#0": (0.21, 68), "Fx#2": (1.01, 68)}, folds) == []
    assert worse_channels({"Fx": (1.96, 238), "Fx#0": (0.21, 68), "Fx#2": (1.04, 68)}, folds) == ["Fx"]
    law = Law("friction_variable", ("LMUX", "LMUY"), "linear")
    narrow = trimmed(law, ["Fx"])
    assert narrow is not None and narrow.targets == ("LMUY",)
    assert trimmed(Law("f", ("LMUX",), "linear"), ["Fx"]) is None
    assert trimmed(CONTROL, ["Fx"]) is None
    assert EffectFit("x", "v", True, {}, {}, {}, 1.0, 0.5, 0.0, 1).rejected is False


def _cornering_campaign(seed: int = 2) -> pd.DataFrame:
    """Cornering at three loads, three sweeps each, with a tread temperature that cycles over the campaign."""
    rng = np.random.default_rng(seed)
    F0 = TYRE["FNOMIN"]
    rows = []
    for _ in range(3):
        for lf in (0.5, 1.0, 1.5):
            a = np.radians(np.linspace(-12, 12, 41))
            rows.append(pd.DataFrame(dict(Fz=lf * F0 * (1 + 0.02 * rng.standard_normal(41)), kappa=0.0, alpha=a,
                                          gamma=0.0, Vx=60 / 3.6, P=TYRE["NOMPRES"])))  # fmt: skip
    df = pd.concat(rows, ignore_index=True)
    df["time"] = np.arange(len(df)) * 0.5
    df["tread_temp"] = 40 + 20 * np.sin(np.arange(len(df)) / 50.0) + rng.standard_normal(len(df))
    return df


def test_lateral_only_effect_leaves_fx_exactly_as_it_was(base_df):
    """Grip falling with tread temperature on Fy only: the law targets LMUY alone, and the extended model
    predicts Fx (and every Fx coefficient) exactly as the model given.  Braking sweeps of the common campaign
    and the cornering sweeps of the cornering campaign (three per load, so that held-out folds test Fy)."""
    corner = _cornering_campaign()
    both = pd.concat([base_df[base_df.alpha == 0.0], corner], ignore_index=True)
    both["time"] = np.arange(len(both)) * 0.5
    sec = _term("LMUY", "linear", "tread_temp", ref=30.0, scale=20.0, c1=-0.12)
    d = _measure(both, sec, {"tread_temp": both.tread_temp.values})
    tyre = _refit(d)
    res = diagnose(d, tyre, progress=False)
    assert res.significant, res.messages
    assert res.ranking[0].variable == "tread_temp"
    assert "LMUY" in res.effect.targets and "LMUX" not in res.effect.targets
    a, b = tyre.evaluate_frame(d), res.extended.evaluate_frame(d)
    np.testing.assert_allclose(a["Fx"].to_numpy(), b["Fx"].to_numpy(), rtol=1e-12, atol=1e-9)
    assert not any(k[1:3] == "DX" or k[1:3] == "KX" for k in res.effect.standard), res.effect.standard
    fy = next(e for e in res.errors if e.channel == "Fy")
    assert fy.rms_after <= 0.5 * fy.rms_before
    for e in res.errors:  # never worse on the held-out condition
        assert e.rms_after <= 1.02 * e.rms_before + 1e-9, e


def test_trail_only_effect_is_found_in_the_aligning_moment():
    """Pneumatic trail falling with tread temperature (Mz only): an LTR law, forces untouched."""
    base_df = _cornering_campaign()
    sec = _term("LTR", "linear", "tread_temp", ref=30.0, scale=20.0, c1=-0.2)
    d = _measure(base_df, sec, {"tread_temp": base_df.tread_temp.values})
    tyre = _refit(d, ("PDY1", "PDY2", "PKY1", "QDZ1", "PEY1"))  # cornering only: no Fx coefficient
    res = diagnose(d, tyre, progress=False)
    assert res.significant, res.messages
    assert res.ranking[0].variable == "tread_temp"
    assert res.effect.targets == ("LTR",), res.effect.targets
    a, b = tyre.evaluate_frame(d), res.extended.evaluate_frame(d)
    for ch in ("Fx", "Fy"):
        np.testing.assert_allclose(a[ch].to_numpy(), b[ch].to_numpy(), rtol=1e-12, atol=1e-9)
    mz = next(e for e in res.errors if e.channel == "Mz")
    assert mz.rms_after <= 0.5 * mz.rms_before


def _warm_up(n: int = 120) -> pd.DataFrame:
    """A free-rolling warm-up at the nominal load (no slip: nothing for the fit)."""
    return pd.DataFrame(dict(Fz=TYRE["FNOMIN"], kappa=0.0, alpha=0.0, gamma=0.0, Vx=60 / 3.6, P=TYRE["NOMPRES"],
                             tread_temp=np.linspace(20, 30, n)))  # fmt: skip


def test_flagged_rows_feed_the_accumulators_only(base_df):
    d = _measure(base_df, None)
    warm = _measure(_warm_up(), None)
    raw = pd.concat([warm.assign(fit_row=False), d.assign(fit_row=True)], ignore_index=True)
    raw["time"] = np.arange(len(raw)) * 0.5
    rows, full = split_fit_rows(raw)
    assert full is not None and len(rows) == len(d) and len(full) == len(raw)
    assert "fit_row" not in rows.columns
    res = diagnose(raw, _refit(d), progress=False)
    assert not res.significant and res.extended is None
    assert len(res.data) == len(d)
    # without the column every row is a fit row; the flag read back from CSV as text is understood
    assert split_fit_rows(d)[1] is None
    rows2, full2 = split_fit_rows(raw.assign(fit_row=raw.fit_row.map({True: "True", False: "False"})))
    assert len(rows2) == len(d) and len(full2) == len(raw)


def test_stiffness_hysteresis_between_up_and_down_sweeps_is_a_stiffness_law():
    """Cornering stiffness higher in the up sweeps than in the down sweeps (rubber loading and unloading): the
    diagnosis names the sweep direction and writes a hysteresis law on LKY (the direction form), not on friction,
    and the held-out Fy error falls to near the noise (2.7 -> 1.4 % of peak, the noise 1 % of peak)."""
    base_df = _cornering_campaign()
    sweep = np.repeat(np.arange(9), 41)
    up = sweep % 2 == 0
    a = base_df.alpha.to_numpy().copy()
    a[~up] = a[~up].reshape(-1, 41)[:, ::-1].ravel()  # every other sweep from +12 to -12 deg
    base_df = base_df.assign(alpha=a, sweep_dir=np.where(up, 1.0, -1.0))
    sec = _term("LKY", "direction", "sweep_dir", ref=0.0, scale=1.0, c1=0.08)
    d = _measure(base_df, sec, {"sweep_dir": base_df.sweep_dir.to_numpy()}).drop(columns="sweep_dir")
    tyre = _refit(d, ("PDY1", "PDY2", "PKY1", "QDZ1", "PEY1"))
    res = diagnose(d, tyre, progress=False)
    assert res.significant, res.messages
    assert res.ranking[0].variable == "sweep_dir"
    assert res.effect.law.form == "direction" and "LKY" in res.effect.targets, (res.effect.name, res.effect.targets)
    fy = next(e for e in res.errors if e.channel == "Fy")
    assert fy.rms_after <= 0.6 * fy.rms_before and fy.rms_pct_after < 1.6, (fy.rms_pct_before, fy.rms_pct_after)


def test_hysteresis_laws_cover_stiffness_and_shape_whatever_the_profiles_link():
    """The sweep direction gets a hysteresis law in the slip stiffness and in the shape as well as in the families
    the per-sweep profiles link to it (none linked: friction) and the force offsets: a stiffness hysteresis the
    profiles missed was never tried (zoo seed 114)."""
    from mftire.diagnosis.effects import effects_for

    laws = {law.name: law for _, law in effects_for("sweep_dir", True, False, 99, ("friction",), ("Fx", "Fy"))}
    assert {"hysteresis_friction", "hysteresis_stiffness", "hysteresis_shape", "hysteresis_shift"} <= set(laws)
    assert laws["hysteresis_stiffness"].targets == ("LKX", "LKY") and laws["hysteresis_shape"].form == "direction"
    lateral = {law.name: law for _, law in effects_for("sweep_dir", True, False, 99, ("friction",), ("Fy",))}
    assert lateral["hysteresis_stiffness"].targets == ("LKY",)


def test_an_input_candidate_gets_its_interaction_with_a_second_variable():
    """A speed effect whose size follows a column (grip changing with wear, more at speed) shows in Vx first: Vx
    gets its interaction law with the second variable (read as the builtin Vx, times the column), besides its
    documented speed law; with no second variable it gets the documented laws only (zoo seed 129)."""
    from mftire.diagnosis.effects import effects_for

    laws = effects_for("Vx", True, False, 2, ("friction",), ("Fy",), second="time")
    inter = [(var, law) for var, law in laws if law.form == "interaction"]
    assert inter == [("Vx", Law("friction_interaction", ("LMUY",), "interaction", variable2="time"))]
    assert {law.name for _, law in laws} >= {"speed_friction", "friction_interaction"}
    assert all(law.form != "interaction" for _, law in effects_for("Vx", True, False, 2, ("friction",), ("Fy",)))


def test_an_input_offset_curved_in_three_levels_gets_a_quadratic_law():
    """A slip-angle offset with an optimum in road temperature tested at three levels: a straight line cannot
    follow it and a per-level table cannot predict a fourth level; the quadratic through three levels is offered
    (zoo seed 122: held-out cut 0 -> 78 %, ceiling 81 %).  With two levels, the linear law only."""
    from mftire.diagnosis.effects import effects_for

    def names(n_levels: int) -> set[str]:
        return {law.name for _, law in effects_for("road_temp", False, False, n_levels, ("shift",), ("Fy",),
                                                    inputs=("ALPHA_OFFSET",))}  # fmt: skip

    assert {"slip_angle_offset", "slip_angle_offset_quadratic"} <= names(3)
    assert "slip_angle_offset" in names(2) and "slip_angle_offset_quadratic" not in names(2)


def test_a_trimmed_fit_keeps_the_law_on_the_channels_it_did_not_make_worse():
    from mftire.diagnosis.effects import trimmed_fit

    law = Law("vertical_shift_threshold", ("LVX", "LVY"), "hinge")
    fit = EffectFit("vertical_shift_threshold", "tread_temp", True, {"EXT1_C1": 0.5},
                    {"EXT1_TARGET": "LVX LVY", "EXT1_FORM": "hinge", "EXT1_C1": 0.5}, {}, 1.0, 0.5, 0.0, 2, law=law,
                    targets=("LVX", "LVY"), refit="all")  # fmt: skip
    narrow = trimmed_fit(fit, ["Fy"])
    assert narrow is not None and narrow.targets == ("LVX",) and narrow.law.targets == ("LVX",)
    assert narrow.section["EXT1_TARGET"] == "LVX" and narrow.section["EXT1_C1"] == 0.5 and narrow.refit == "all"
    assert fit.targets == ("LVX", "LVY")  # the original is not changed
    assert trimmed_fit(fit, ["Fx", "Fy"]) is None and trimmed_fit(fit, ["Mz"]) is None


def _offset_problem(section: dict, column: np.ndarray | None = None):
    """The common campaign measured with ``section`` (a law in ``rim_temp``, constant per sweep, 30-60 °C) and the
    diagnosis' training problem on the true tyre (no refit: the base holds no part of the effect)."""
    from mftire.diagnosis.effects import make_problem

    d = with_sweeps(_campaign())
    temp = 30.0 + 30.0 * (d["sweep_id"].factorize()[0] % 7) / 6.0 if column is None else column
    d["rim_temp"] = temp
    m = _measure(d, section, {"rim_temp": d["rim_temp"].to_numpy()})
    return make_problem(TYRE, with_sweeps(m), ("Fx", "Fy", "Mz")), m["rim_temp"].to_numpy()


def test_an_offset_law_holds_its_constant_part():
    """A lateral force offset of one sign that grows with rim temperature, Fz·0.02·(T − 20)/10 (never zero in the
    data): the offset law carries its own constant (a one-level table term, f = 1 + C1), since no refitted
    coefficient offsets a force, and a law zero at the median temperature could not hold it (zoo seed 45: held-out
    cut 1 -> 71 %).  Recovered: slope and constant."""
    from mftire.diagnosis.effects import fit_effect

    sec = _term("FY_OFFSET", "linear", "rim_temp", ref=20.0, scale=10.0, c1=0.02)
    prob, temp = _offset_problem(sec)
    fit = fit_effect(prob, Law("shift_variable", ("FY_OFFSET",), "linear"), "rim_temp", temp, refit_base=False)
    forms = {k: v for k, v in fit.section.items() if k.endswith("_FORM")}
    assert sorted(forms.values()) == ["linear", "table"], fit.section
    assert fit.removed > 0.6, fit.removed  # the rest is the 1 % noise of Fx, Fy and Mz
    lin = next(k[:-5] for k, v in forms.items() if v == "linear")
    tab = next(k[:-5] for k, v in forms.items() if v == "table")
    ref, scale = fit.section[lin + "_REF"], fit.section[lin + "_SCALE"]
    # Fz·(C1' + C1·(T − REF)/SCALE) = Fz·0.002·(T − 20): slope and value at REF as generated
    assert fit.section[lin + "_C1"] / scale == pytest.approx(0.002, rel=0.1)
    assert fit.section[tab + "_C1"] == pytest.approx(0.002 * (ref - 20.0), rel=0.05)
    # a slip-angle offset carries its constant too (zoo seed 107: on one road surface); a camber offset does not
    for target, name, constant in (("ALPHA_OFFSET", "slip_angle_offset", True),
                                   ("GAMMA_OFFSET", "camber_offset", False), ("LMUY", "friction_variable", False)):
        f = fit_effect(prob, Law(name, (target,), "linear"), "rim_temp", temp, refit_base=False)
        assert ("table" in f.section.values()) == constant, (target, f.section)


def test_a_horizontal_shift_law_refits_the_shift_it_scales():
    """A horizontal shift of Fx growing with rim temperature on a tyre whose fitted shift is zero (PHX1 = 0): a
    law LHX·(1 + C1·z) scales nothing unless PHX1 is refitted with it (zoo seed 191: no law -> held-out cut 84 %).
    PHX1 is refitted with a law on LHX, and only then; a vertical-shift law keeps PVX1."""
    from mftire.diagnosis.effects import SHIFT_COEFFICIENTS, fit_effect, make_problem

    assert SHIFT_COEFFICIENTS == {"LHX": "PHX1", "LHY": "PHY1"}
    flat = dict(TYRE.flat)
    flat.update(PHX1=0.0, PHX2=0.0)
    base = type(TYRE)(flat)
    d = with_sweeps(_campaign())
    d["rim_temp"] = 30.0 + 30.0 * (d["sweep_id"].factorize()[0] % 7) / 6.0
    shifted = dict(flat)
    shifted[SECTION] = _term("KAPPA_OFFSET", "linear", "rim_temp", ref=45.0, scale=15.0, c1=0.01)
    out = type(TYRE)(shifted).evaluate(d.Fz.values, d.kappa.values, d.alpha.values, d.gamma.values, Vx=d.Vx.values,
                                       P=d.P.values, rim_temp=d.rim_temp.values)  # fmt: skip
    m = d.copy()
    for ch in ("Fx", "Fy", "Mz"):
        m[ch] = out[ch]
    prob = make_problem(base, m, ("Fx",))
    temp = m["rim_temp"].to_numpy()
    fit = fit_effect(prob, Law("horizontal_shift_variable", ("LHX",), "linear"), "rim_temp", temp)
    assert "PHX1" in fit.standard and abs(fit.standard["PHX1"]) > 1e-4
    assert fit.removed > 0.8, fit.removed
    vfit = fit_effect(prob, Law("vertical_shift_variable", ("LVX",), "linear"), "rim_temp", temp)
    assert "PVX1" not in vfit.standard and "PHX1" not in vfit.standard


def test_loads_tested_in_blocks_still_hold_out_the_last_tests():
    """The common campaign tests its loads in blocks, so its last sweeps are at a load no earlier sweep had.  The
    plain "last tests" cannot be held out (that would judge an extrapolation in load); the last sweeps are held out
    all the same, labelled as a load block, because a law fitted to an effect that drifts along the programme in a
    column that does not carry the drift holds on the earlier blocks only (zoo seed 49: a law in Vx made the last
    load block's Mz 36 % worse).  A programme whose last tests repeat earlier conditions keeps the plain label."""
    from mftire.diagnosis.diagnose import extra_conditions

    noise = {"Fx": 10.0, "Fy": 10.0, "Mz": 1.0}
    d = with_sweeps(_measure(_campaign(), None))
    d["time"] = np.arange(len(d)) * 0.5
    conds = dict(extra_conditions(d, TYRE, TYRE, ("Fx", "Fy", "Mz"), noise, "rim_temp"))
    rows = conds["the last tests (a load block)"]
    assert set(d.loc[rows, "Fz_set"]) == {d["Fz_set"].iloc[-1]} and rows[-1] and not rows[0]
    assert "the last tests" not in conds
    # the programme run twice: the last tests repeat conditions tested before
    e = pd.concat([d, d.assign(sweep_id=d["sweep_id"].astype(str) + "b")], ignore_index=True)
    e["time"] = np.arange(len(e)) * 0.5
    conds = dict(extra_conditions(e, TYRE, TYRE, ("Fx", "Fy", "Mz"), noise, "rim_temp"))
    assert "the last tests" in conds and "the last tests (a load block)" not in conds


def test_an_aligning_moment_effect_is_offered_an_effective_pressure():
    """A pressure that rises with tread temperature while the logged P stays cold acts on the trail too (PPZ1,
    Besselink et al. 2010 eq A60); when a base fit over blocked loads has absorbed its force part, Mz alone shows it
    and only the aligning moment's families are tried: the trail's family offers the effective pressure (zoo seed
    97: held-out cut 36 -> 55 %).  The residual torque's does not (no pressure term in Dr at zero camber)."""
    from mftire.diagnosis.effects import effects_for

    def names(family: str) -> set[str]:
        return {law.name for _, law in effects_for("tread_depth", False, False, 6, (family,), ("Mz",),
                                                    inputs=("P_FACTOR",))}  # fmt: skip

    assert {"effective_pressure", "effective_pressure_quadratic"} <= names("trail")
    assert not any(n.startswith("effective_pressure") for n in names("residual_torque"))


def test_full_refit_keeps_the_sweeps_it_is_given(monkeypatch):
    """Cornering sweeps thinned to a few steps that return to alpha = 0 (as rows are left out around the diagnosis's
    held-out condition), each followed by a braking sweep at the same set points (zoo seed 1152): the grouping in row
    order read each pair as one combined sweep, and the diagnosis's full refit then fitted the combined-slip
    coefficients to pure slip data (RBX2 went to its bound, -500)."""
    from mftire.diagnosis.effects import _full_refit
    from mftire.fitting.fitter import _classify_rows
    from mftire.segmentation.grouping import group_sweeps

    rng = np.random.default_rng(4)
    kappa = -0.25 * (np.arange(14) / 13) ** 1.5
    steps = (np.radians([-1.67, 0.0, 10.0, 6.67, 1.67, 0.0, -5.0]), np.radians([-6.67, 0.0, 3.33, 8.33, 0.0, -5.0]))
    parts, sid = [], 0
    for lf in (0.6, 1.0, 1.4):
        for a in steps:
            fz = lf * TYRE["FNOMIN"] * (1 + 0.01 * rng.standard_normal(a.size + kappa.size))
            parts += [pd.DataFrame(dict(Fz=fz[: a.size], kappa=0.0, alpha=a, sweep_id=sid)),
                      pd.DataFrame(dict(Fz=fz[a.size:], kappa=kappa, alpha=0.0, sweep_id=sid + 1))]
            sid += 2
    df = pd.concat(parts, ignore_index=True).assign(gamma=0.0, Vx=22.0, P=TYRE["NOMPRES"])
    df = _measure(df, None)
    # the grouping in row order reads them as pure sweeps (mftire.segmentation.grouping._split_runs: a slip that
    # steps away from its level and back has left it) ...
    regrouped = _classify_rows(group_sweeps(df.drop(columns="sweep_id")))
    assert set(regrouped["kind"]) == {"pure_lateral", "pure_longitudinal"}
    assert regrouped.groupby("sweep_id").ngroups == sid
    # ... and the full refit hands the fitter the diagnosis's sweeps (found on the full data), whatever its own
    # grouping in row order would make of thinned rows
    import mftire.fitting.fitter as fitter

    seen = []
    real = fitter.fit_tir

    def spy(table, *args, **kwargs):
        seen.append(table)
        return real(table, *args, **kwargs)

    monkeypatch.setattr(fitter, "fit_tir", spy)
    out = _full_refit(df, TYRE)
    assert (seen[0]["source"].to_numpy() == df["sweep_id"].astype(str).to_numpy()).all()
    combined = ("RBX1", "RBX2", "RCX1", "REX1", "RHX1", "RBY1", "RBY2", "RCY1", "RHY1")
    assert {k: out[k] for k in combined} == {k: TYRE[k] for k in combined}
    assert out["PDX1"] != TYRE["PDX1"]  # the pure-slip stages were refitted


def test_an_input_law_frees_the_channels_that_read_its_input_through_the_combined_slip():
    """A slip-angle offset acts on Fy and Mz, and also lowers the braking force through the combined-slip weighting
    (Pacejka 2012 eqs 4.E54-4.E57): its refit frees the Fx coefficients that absorbed it (zoo seed 1108: no law ->
    a slip-angle offset quadratic in hardness, held-out cut 90 %).  A longitudinal-slip offset frees Fy (4.E58-4.E67)
    and, through Fy, Mz; a law on Fx's grip frees Fx only."""
    from mftire.diagnosis.effects import refit_channels_of

    assert refit_channels_of(Law("slip_angle_offset", ("ALPHA_OFFSET",), "linear")) == ("Fx", "Fy", "Mz")
    assert refit_channels_of(Law("slip_ratio_offset", ("KAPPA_OFFSET",), "linear")) == ("Fx", "Fy", "Mz")
    assert refit_channels_of(Law("shift_variable", ("FY_OFFSET",), "linear")) == ("Fy", "Mz")
    assert refit_channels_of(Law("friction_variable", ("LMUX",), "linear")) == ("Fx",)
    assert refit_channels_of(CONTROL) is None


def test_the_elapsed_time_is_never_the_second_variable_of_an_interaction():
    """Loads tested in blocks along a drifting programme: an interaction of a temperature with the clock fits the
    blocks one by one (zoo seed 1171: Mz +135 % on new runs).  The other columns stay partners."""
    from mftire.diagnosis.candidates import interaction_partners

    values = {"track_temp": np.arange(3.0), "time": np.arange(3.0), "tread_depth": np.arange(3.0)}
    assert set(interaction_partners(values, "track_temp", "time")) == {"tread_depth"}
    assert set(interaction_partners(values, "track_temp", None)) == {"time", "tread_depth"}
    assert set(interaction_partners(values, "time", "time")) == {"track_temp", "tread_depth"}
