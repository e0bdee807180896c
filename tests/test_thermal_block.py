"""The thermal block of the transient tyre (issue 22): simulate(thermal=True) and the transient FMU.

* C and Python agree on every term of the block (gas law, friction power, rolling and hysteresis loss,
  convection, node rates, the implicit step, the laws reading the nodes) at random points (probe library);
* the FMU (FMI 2 Model Exchange) integrated like ``simulate`` agrees with ``simulate(thermal=True)`` to 1e-6
  along a reduced stint of the shipped thermal run; its Co-Simulation step equals the Python mirror
  (:class:`mftire.transient.TransientStepper`) (full stint: ``python validation/thermal_block.py``);
* constant conditions: the states reach the analytic steady state of the node equations (heat.steady_state);
* fmpy validation (FMI 2, FMI 3), the transient fuzz with the thermal inputs (reduced), bad input.
"""

from __future__ import annotations

import ctypes
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import load_validation, needs_c_compiler
from hypothesis import given, settings
from hypothesis import strategies as st

from mftire.errors import MftireInputError
from mftire.transient import TransientTyre, simulate

ROOT = Path(__file__).resolve().parents[1]
PLAIN = ROOT / "tirfiles" / "MF61_255-55R20_mfeval-jl.tir"


@pytest.fixture(scope="module")
def block():
    return load_validation("thermal_block")


@pytest.fixture(scope="module")
def tyre(block):
    return block.thermal_tir()


@pytest.fixture(scope="module")
def model(tyre):
    return TransientTyre(tyre, thermal=True)


@pytest.fixture(scope="module")
def shipped(block):
    """The shipped thermal .tir (mftire fit-thermal of the shipped run)."""
    return block.shipped_tir()


@pytest.fixture(scope="module")
def fmus(shipped, tmp_path_factory):
    from mftire.fmu.export import export_fmu

    d = tmp_path_factory.mktemp("thermal_fmu")
    return {v: export_fmu(shipped, d / f"thermal{v}.fmu", fmi_version=v, transient=True) for v in (2, 3)}


@needs_c_compiler
def test_c_and_python_agree_on_every_term(tyre, model, tmp_path):
    """The probe computes each term of the block in C; Python computes it with mftire.thermal's functions."""
    from mftire.fmu.transient_export import build_probe_library
    from mftire.transient.slip_dynamics import advance_thermal

    lib = ctypes.CDLL(str(build_probe_library(tyre, tmp_path)))
    D = ctypes.c_double
    rng = np.random.default_rng(22)
    laws = 0
    for _ in range(200):
        ins = dict(Fz=rng.uniform(0, 9000), Vx=rng.uniform(-30, 30) * rng.choice([1.0, 0.02, 0.0]),
                   Vy=rng.uniform(-3, 3), omega=rng.uniform(-90, 90), gamma=rng.uniform(-0.1, 0.1),
                   P=rng.choice([rng.uniform(2.0e5, 2.6e5), 0.0, np.nan]), muRoad=rng.uniform(0.3, 1.2),
                   yawRate=rng.uniform(-1, 1), T_ambient=rng.uniform(-10, 40), T_road=rng.uniform(-10, 60))  # fmt: skip
        x = np.r_[rng.normal(0.0, 0.05, 2), rng.uniform(0.0, 120.0, 3)]
        h = 10.0 ** rng.uniform(-4, 1)
        dx, q, P, y, Tn = (D * 5)(), (D * 3)(), D(), (D * 7)(), (D * 3)()
        assert lib.mt_probe_thermal(111, (D * 10)(*ins.values()), (D * 5)(*x), D(h), dx, q, ctypes.byref(P), y,
                                    Tn) == 0  # fmt: skip
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            kin = model._kin(x, ins)
            out = model.outputs_from(kin, x[0], x[1])
            py_dx = model.all_derivatives(x, **ins)
            py_q = [float(v) for v in model.heat(kin, out)]
            py_T = advance_thermal(model, kin, out, h, ins["T_ambient"], ins["T_road"])
        np.testing.assert_allclose(dx[:], py_dx, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(q[:], py_q, rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(Tn[:], py_T, rtol=1e-13)
        assert P.value == pytest.approx(float(kin.P_hot), rel=1e-14)
        po = [float(out[k]) for k in ("Fx", "Fy", "Mz", "Mx", "My", "kappa_t", "alpha_t")]
        np.testing.assert_allclose(y[:], po, rtol=1e-9, atol=1e-9)
        laws += abs(x[2] - 60.0) > 5.0  # the grip law acts (away from its reference)
    assert laws > 100


def test_the_laws_and_the_gas_law_act(tyre, model):
    """A hot surface lowers the grip by the law's own factor; a hot gas raises the MF's pressure by Gay-Lussac."""
    from mftire.thermal.heat import hot_pressure

    ins = dict(Fz=4000.0, Vx=20.0, Vy=1.0, omega=20.0 / 0.35, P=2.3e5)
    cold = model.outputs((0.0, 0.3, 60.0, 60.0, 20.0), **ins)
    hot = model.outputs((0.0, 0.3, 110.0, 60.0, 20.0), **ins)  # surface hot, bulk and gas as before
    z = (110.0 - 60.0) / 50.0
    assert float(hot["muy"] / cold["muy"]) == pytest.approx(1.0 - 0.1 * z - 0.05 * z * z, rel=1e-12)
    assert float(hot["Kya"]) == float(cold["Kya"])  # the stiffness law reads the bulk
    stiff = model.outputs((0.0, 0.3, 60.0, 100.0, 20.0), **ins)
    assert float(stiff["Kya"] / cold["Kya"]) == pytest.approx(1.0 - 0.05 * (100.0 - 60.0) / 50.0, rel=1e-12)
    assert float(cold["P_hot"]) == pytest.approx(2.3e5, rel=1e-15)  # gas at the cold temperature
    gas = model.outputs((0.0, 0.3, 60.0, 60.0, 70.0), **ins)
    assert float(gas["P_hot"]) == pytest.approx(float(hot_pressure(70.0, 2.3e5, 20.0)), rel=1e-15)
    assert float(gas["P_hot"]) == pytest.approx((2.3e5 + 101325.0) * 343.15 / 293.15 - 101325.0, rel=1e-12)
    assert float(gas["Fy"]) != float(cold["Fy"])  # the hot pressure enters the MF's pressure terms


def test_constant_conditions_reach_the_analytic_steady_state(tyre, model):
    """Held inputs, the slip states at their equilibrium: large backward-Euler steps of the block (L-stable)
    reach heat.steady_state of the heat at the final state (a fixed point of the coupling: the laws and the
    pressure move the forces, the forces the heat), and its gas node is the bulk temperature."""
    from mftire.thermal.heat import steady_state
    from mftire.transient.slip_dynamics import advance_thermal

    th = model.thermal
    ins = dict(Fz=4000.0, Vx=20.0, Vy=0.4, omega=20.0 / 0.3526)
    T = (20.0, 20.0, 20.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for _ in range(150):
            kin = model.kinematics(**ins, T=T)
            u, v = -kin.Vsx * kin.sigx / 20.0, kin.Vsy * kin.sigy / 20.0  # the lag's equilibrium (§7.2.1)
            out = model.outputs_from(kin, u, v)
            T = advance_thermal(model, kin, out, 50.0, 25.0, 35.0)
        kin = model.kinematics(**ins, T=T)
        out = model.outputs_from(kin, -kin.Vsx * kin.sigx / 20.0, kin.Vsy * kin.sigy / 20.0)
        q_s, q_b, g_air = (float(v) for v in model.heat(kin, out))
    ref = steady_state(q_s, q_b, g_air, 25.0, 35.0, th.g_surface_bulk, th.g_bulk_gas, th.g_bulk_ambient, th.g_road)
    np.testing.assert_allclose(T, ref, rtol=1e-9)
    assert T[0] > 40.0 and T[2] == pytest.approx(T[1], rel=1e-9)
    assert np.all(np.abs(model.all_derivatives([u, v, *T], **ins, T_ambient=25.0, T_road=35.0)[2:]) < 1e-9)


@needs_c_compiler
def test_fmu_agrees_with_simulate_over_a_stint(block, shipped, fmus):
    """Issue 22: the thermal block in the FMU agrees with simulate(thermal=True) to 1e-6 (the shipped thermal
    .tir on a reduced stint of the shipped run; measured on 60 s by validation/thermal_block.py); CS equals its
    Python mirror."""
    tyre = shipped
    s = block.stint(seconds=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ref = simulate(tyre, s["t"], **{k: s[k] for k in ("Fz", "Vx", "Vy", "omega", "gamma")}, thermal=True,
                       T_ambient=s["T_ambient"], T_road=s["T_road"], T0=block.T0)  # fmt: skip
    assert ref["T_surface"].iloc[-1] > block.T0[0] + 1.0  # the stint heats the surface
    me = block.differences(block.fmu_model_exchange(fmus[2], s), {k: ref[k].to_numpy() for k in block.CHANNELS})
    assert max(me.values()) <= 1e-6, me
    short = {k: v[:4] for k, v in s.items()}
    a, b, _ = block.fmu_co_simulation(fmus[3], short, tyre=tyre)
    assert max(block.differences(a, b).values()) <= 1e-12


@needs_c_compiler
def test_fmpy_validation_and_simulation(fmus):
    import fmpy
    from fmpy.validation import validate_fmu

    for v, path in fmus.items():
        assert validate_fmu(str(path)) == [], v
        md = fmpy.read_model_description(str(path))
        names = {x.name: x for x in md.modelVariables}
        assert {"T_ambient", "T_road"} <= {n for n, x in names.items() if x.causality == "input"}
        assert {"T_surface", "T_bulk", "T_gas", "P_hot"} <= {n for n, x in names.items() if x.causality == "output"}
        assert names["TH_T_INIT_SURFACE"].variability == "fixed"
        assert len(md.derivatives) == 5
    res = fmpy.simulate_fmu(str(fmus[2]), fmi_type="CoSimulation", stop_time=0.2, output_interval=1e-3,
                            start_values={"TH_T_INIT_SURFACE": 50.0, "Vy": 1.0, "T_ambient": 10.0},
                            output=["T_surface", "T_gas", "P_hot", "Fy"], validate=True)  # fmt: skip
    assert np.isfinite(res["T_surface"]).all() and res["T_surface"][0] == 50.0
    assert res["T_surface"][-1] != 50.0 and abs(res["Fy"][-1]) > 100.0


@needs_c_compiler
@pytest.mark.parametrize("interface", ["CS", "ME"])
def test_fuzz_thermal_fmu(fmus, interface):
    """The transient fuzz with T_ambient, T_road fuzzed too (reduced; full: validation/transient_fuzz.py
    --thermal): no non-finite output, state or derivative; ME after the fuzz equals a fresh instance."""
    fz = load_validation("transient_fuzz")
    r = fz.fuzz(fmus[2], interface, 1500, seed=31 if interface == "CS" else 32)
    assert r["bad"] == [], r["bad"][:3]
    assert r["errors"] == 0 and r["guard_warnings"] > 0
    assert (r["diff"] is None) == (interface == "CS")
    assert interface == "CS" or r["diff"] <= 1e-12


def test_bad_input_is_a_clear_error(tyre, tmp_path, capsys):
    from mftire.cli import main
    from mftire.fmu.build import FMUExportError
    from mftire.fmu.export import export_fmu
    from mftire.tyre import load

    plain = load(PLAIN)
    with pytest.raises(MftireInputError, match=r"MFTIRE_THERMAL\] section"):
        simulate(plain, [0.0, 0.1], thermal=True)
    with pytest.raises(FMUExportError, match=r"MFTIRE_THERMAL\] section"):
        export_fmu(plain, tmp_path / "x.fmu", transient=True, thermal=True)
    out = tmp_path / "x.fmu"
    assert main(["export-fmu", str(PLAIN), "--thermal", "--output", str(out)]) == 2
    assert "MFTIRE_THERMAL" in capsys.readouterr().err and not out.exists()
    t = np.linspace(0.0, 0.1, 3)
    with pytest.raises(MftireInputError, match="T_ambient must be finite"):
        simulate(tyre, t, thermal=True, T_ambient=[20.0, math.nan, 20.0])
    with pytest.raises(MftireInputError, match="T_road must be finite"):
        simulate(tyre, t, thermal=True, T_road=math.inf)
    with pytest.raises(MftireInputError, match="T0 must be three finite"):
        simulate(tyre, t, thermal=True, T0=(20.0, math.nan, 20.0))
    with pytest.raises(MftireInputError, match="thermal block"):
        simulate(plain, t, T_ambient=20.0)
    # the thermal .tir without its block: its laws cannot be given to the plain transient model
    with pytest.raises(MftireInputError, match="thermal"):
        TransientTyre(tyre)


@needs_c_compiler
def test_fmu_refuses_bad_thermal_parameters(fmus):
    from mftire.fmu.host import FMUTyre

    messages = []
    s = FMUTyre(fmus[2], "CS", instance_name="bad", logger=lambda st, cat, msg: messages.append(msg))
    try:
        for key, value in (("TH_CAP_SURFACE", 0.0), ("TH_G_ROAD", -1.0), ("TH_T_INIT_GAS", math.nan),
                           ("TH_T_INIT_BULK", -300.0), ("TH_PRESSURE", 0.5)):  # fmt: skip
            with pytest.raises(Exception):  # noqa: B017 (fmpy raises its own exception type per version)
                s.set({key: value})
        assert any("TH_CAP_SURFACE" in m and "> 0" in m for m in messages)
        assert any("TH_PRESSURE" in m and "0 or 1" in m for m in messages)
        # a NaN temperature input: the last good value is held, with a warning naming the input
        s.set({"T_ambient": 25.0, "Vy": 0.5})
        s.fmu.doStep(0.0, 1e-3)
        good = s.get(["T_surface", "Fy"])
        s.set({"T_ambient": math.nan})
        s.fmu.doStep(1e-3, 1e-3)
        held = s.get(["T_surface", "Fy", "T_ambient"])
        assert all(map(math.isfinite, held[:2])) and held[0] != good[0]
        assert any("input 'T_ambient' not finite" in m for m in messages)
    finally:
        s.close()


def test_a_plain_tir_gives_the_plain_transient_fmu():
    """No [MFTIRE_THERMAL]: the transient FMU's variables and C configuration are those without the block."""
    from mftire.fmu.transient_export import _check_transient, generate_transient_sources, output_names

    flat, _, th = _check_transient(PLAIN)
    assert th is None
    variables, files = generate_transient_sources(flat, "plain")
    names = {v.name for v in variables}
    assert not names & {"T_ambient", "T_road", "T_surface", "P_hot", "T_s", "TH_CAP_SURFACE"}
    assert [v.name for v in variables if v.kind == "output"] == output_names()
    assert "#define MT_THERMAL 0" in files["mt_config_gen.h"] and "#define MT_N_STATES 2" in files["mt_config_gen.h"]
    assert "MT_STATE_START[2]" in files["mt_model_gen.h"]


@settings(max_examples=80, deadline=None)
@given(caps=st.tuples(*[st.floats(10.0, 1e5)] * 3), g=st.tuples(*[st.floats(0.0, 500.0)] * 5),
       T=st.tuples(*[st.floats(-40.0, 200.0)] * 3), Ta=st.floats(-40.0, 60.0), Tr=st.floats(-40.0, 80.0),
       q=st.tuples(st.floats(0.0, 5e4), st.floats(0.0, 5e3)), dt=st.floats(1e-4, 100.0))  # fmt: skip
def test_node_rates_are_the_equations_of_the_implicit_step(caps, g, T, Ta, Tr, q, dt):
    """heat.node_rates (the Model Exchange derivatives) and heat.implicit_step (the Co-Simulation step) are the
    same node equations: the backward-Euler step satisfies C·(T⁺ − T)/dt = C·rates(T⁺) exactly."""
    from mftire.thermal.heat import implicit_step, node_rates

    g_air, g_sb, g_bg, g_ba, g_road = g
    Tn = implicit_step(T, dt, q[0], q[1], g_air, Ta, Tr, caps, g_sb, g_bg, g_ba, g_road)
    rates = node_rates(Tn, q[0], q[1], g_air, Ta, Tr, caps, g_sb, g_bg, g_ba, g_road)
    for i in range(3):
        flux = caps[i] * rates[i]  # W
        scale = q[0] + q[1] + sum(g) * (abs(Tn[i]) + abs(T[i]) + abs(Ta) + abs(Tr) + 1.0) + caps[i] / dt * abs(T[i])
        assert abs(caps[i] * (Tn[i] - T[i]) / dt - flux) <= 1e-10 * scale
