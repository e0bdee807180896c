"""Transient tyre (issue 13): relaxation-length slip dynamics, standstill, Python and FMU.

Analytic references: in the linear range at constant speed the lateral slip follows
tan(alpha_t) = (Vy/Vx)·(1 - exp(-t·Vx/sigma_alpha)) (Pacejka 2012 §7.2.1); after 20
relaxation lengths the transient model equals the steady-state evaluator.
"""

from __future__ import annotations

import ctypes
import warnings

import numpy as np
import pytest
from conftest import REFERENCE_TYRES, needs_c_compiler
from scipy.integrate import solve_ivp

from mftire.errors import MftireInputError
from mftire.fmu.transient_export import output_names
from mftire.transient import FIRST_OUTPUTS, TransientTyre, simulate, step_exact
from mftire.tyre import load

TIR = REFERENCE_TYRES["JuliaMF61"]
FZ, VX = 4000.0, 10.0


@pytest.fixture(scope="module")
def tyre():
    return load(TIR)


@pytest.fixture(scope="module")
def model(tyre):
    return TransientTyre(tyre)


def _free_rolling_omega(model, Fz, Vx):
    om = Vx / model.tyre["UNLOADED_RADIUS"]
    for _ in range(20):
        om = Vx / float(model.kinematics(Fz=Fz, Vx=Vx, omega=om).zero["Re"])
    return om


def _lateral_step_reference(model, t, Vy):
    om = _free_rolling_omega(model, FZ, VX)
    kin = model.kinematics(Fz=FZ, Vx=VX, Vy=Vy, omega=om)
    T = float(kin.sigy) / VX
    return om, np.arctan(Vy / VX * (1.0 - np.exp(-t / T))), T


def test_lateral_step_python(model, tyre):
    t = np.linspace(0.0, 0.3, 61)
    Vy = 0.02  # 2 mrad: linear range
    om, ref, T = _lateral_step_reference(model, t, Vy)
    assert 0.01 < T < 0.1
    res = simulate(tyre, t, Fz=FZ, Vx=VX, Vy=Vy, omega=om)
    assert list(res.columns[: len(FIRST_OUTPUTS)]) == list(FIRST_OUTPUTS)
    assert set(output_names()) <= set(res.columns)  # every FMU output is a column of the Python result
    final = np.arctan(Vy / VX)
    assert np.max(np.abs(res["alpha_t"].to_numpy() - ref)) < 1e-3 * final
    # the force follows the same lag in the linear range (offset at t = 0 removed)
    fy = res["Fy"].to_numpy()
    ss = tyre.evaluate(FZ, 0.0, final, Vx=VX, omega=om)["Fy"]
    lag = (fy - fy[0]) / (float(ss) - fy[0])
    np.testing.assert_allclose(lag, 1.0 - np.exp(-t / T), atol=2e-3)


def test_steady_state_after_20_relaxation_lengths(model, tyre):
    om = _free_rolling_omega(model, FZ, VX) * 1.05  # 5 % drive slip
    Vy = -0.4
    kin = model.kinematics(Fz=FZ, Vx=VX, Vy=Vy, omega=om, gamma=0.02)
    t_end = 20.0 * float(max(kin.sigx, kin.sigy)) / VX
    res = simulate(tyre, np.linspace(0.0, t_end, 201), Fz=FZ, Vx=VX, Vy=Vy, omega=om, gamma=0.02, rtol=1e-11,
                   atol=1e-14)  # fmt: skip
    kappa = (om * float(kin.zero["Re"]) - VX) / VX
    alpha = np.arctan(Vy / VX)
    ss = tyre.evaluate(FZ, kappa, alpha, 0.02, Vx=VX, omega=om)
    last = res.iloc[-1]
    assert abs(last["kappa_t"] - kappa) < 1e-6 * abs(kappa)
    assert abs(last["alpha_t"] - alpha) < 1e-6 * abs(alpha)
    for name in ("Fx", "Fy", "Mz", "Mx", "My"):
        assert abs(last[name] - float(ss[name])) <= 1e-6 * max(abs(float(ss[name])), 1.0), name


def test_standstill_zero_forces_no_nan(model):
    for omega in (0.0, 1e-12):
        out = model.outputs([0.0, 0.0], Fz=FZ, Vx=0.0, Vy=0.0, omega=omega)
        assert all(np.isfinite(float(v)) for v in out.values())
        for name in ("Fx", "Fy", "Mz", "My"):
            assert abs(float(out[name])) < 1e-6, name
        d = model.derivatives([0.0, 0.0], Fz=FZ, Vx=0.0, Vy=0.0, omega=omega)
        assert np.all(np.abs(d) < 1e-9)
    # zero load, zero speed, NaN inputs: finite
    out = model.outputs([1e-3, -1e-3], Fz=0.0, Vx=0.0, Vy=float("nan"), omega=float("nan"))
    assert all(np.isfinite(float(v)) for v in out.values())


def test_standstill_is_a_damped_spring(model):
    """At rest the tyre force is Cx·(u + tau·du/dt) in the linear range (low-speed model)."""
    kin = model.kinematics(Fz=FZ, Vx=0.0, omega=0.0)
    u = 2e-4
    out = model.outputs_from(kin, u, 0.0)
    Cx = float(kin.zero["Kxk"]) / float(kin.sigx)
    assert abs(float(out["Fx"]) - Cx * u) < 0.02 * Cx * u
    kin = model.kinematics(Fz=FZ, Vx=0.01, omega=0.0)  # sliding forward slowly: damping opposes
    out2 = model.outputs_from(kin, u, 0.0)
    assert float(out2["Fx"]) < float(out["Fx"])


def _parked_on_slope(model, grade=0.2, mass=425.0, t_end=4.0):
    g, th = 9.81, np.arctan(grade)
    Fz = mass * g * np.cos(th)

    def rhs(_t, s):
        Vx, u, v = s
        kin = model.kinematics(Fz=Fz, Vx=Vx, omega=0.0)  # wheel held by the brake
        du, dv = model.rates(kin, u, v)
        Fx = float(model.outputs_from(kin, u, v)["Fx"])
        return [(Fx - mass * g * np.sin(th)) / mass, float(du), float(dv)]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return solve_ivp(rhs, (0.0, t_end), [0.0, 0.0, 0.0], method="LSODA", rtol=1e-8, atol=1e-11, max_step=0.01,
                         dense_output=True)  # fmt: skip


def test_parked_on_20_percent_slope_holds(model):
    sol = _parked_on_slope(model)
    assert sol.success
    t = np.linspace(2.0, 4.0, 201)
    Vx = sol.sol(t)[0]
    assert np.max(np.abs(Vx)) < 1e-3  # drift below 1 mm/s after settling
    u = sol.sol(4.0)[1]
    assert 0.0 < u < 0.02  # held by a few millimetres of deflection


def test_launch_from_rest_no_force_spike(model, tyre):
    mass, J, torque, Fz = 425.0, 1.2, 2500.0, 4000.0

    def rhs(t, s):
        Vx, om, u, v = s
        kin = model.kinematics(Fz=Fz, Vx=Vx, omega=om)
        du, dv = model.rates(kin, u, v)
        Fx = float(model.outputs_from(kin, u, v)["Fx"])
        drive = torque * min(t / 0.05, 1.0)
        return [Fx / mass, (drive - float(kin.zero["Re"]) * Fx) / J, float(du), float(dv)]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sol = solve_ivp(rhs, (0.0, 1.0), [0.0, 0.0, 0.0, 0.0], method="LSODA", rtol=1e-8, atol=1e-11,
                        max_step=0.002, dense_output=True)  # fmt: skip
        t = np.linspace(0.0, 1.0, 401)
        S = sol.sol(t)
        kin = model.kinematics(Fz=Fz, Vx=S[0], omega=S[1])
        Fx = model.outputs_from(kin, S[2], S[3])["Fx"]
        # steady-state envelope of the model: the MF curve, rolling offsets removed below VXLOW
        kap = np.linspace(-1.0, 1.0, 4001)
        peak = 0.0
        for V in (0.0, 0.25, 0.5, 1.0, 5.0, 10.0):
            k0 = model.kinematics(Fz=Fz, Vx=V, omega=0.0)
            curve = tyre.evaluate(Fz, kap, 0.0, Vx=max(V, tyre["VXLOW"]), omega=1e-300)["Fx"]
            peak = max(peak, float(np.max(curve - float(k0.w) * float(k0.zero["Fx"]))))
        plain_peak = float(np.max(tyre.evaluate(Fz, kap, 0.0, Vx=10.0)["Fx"]))
    assert S[0, -1] > 1.0  # it launched
    assert np.all(np.isfinite(Fx))
    assert np.max(Fx) <= peak * (1.0 + 1e-9)
    assert np.max(Fx) <= plain_peak + abs(float(model.kinematics(Fz=Fz, Vx=0.0).zero["Fx"])) + 1e-6


def test_reversal_is_smooth(model):
    Vx = np.linspace(-2.0, 2.0, 401)
    out = model.outputs([2e-3, 1e-3], Fz=FZ, Vx=Vx, Vy=0.0, omega=0.0)
    for name in ("Fx", "Fy", "Mz", "My"):
        jumps = np.abs(np.diff(out[name]))
        assert np.all(np.isfinite(out[name]))
        assert np.max(jumps) < 0.05 * max(np.max(np.abs(out[name])), 1.0), name


def test_exponential_step_is_exact_for_the_linear_lag(tyre):
    model = TransientTyre(tyre, constants={"TR_SAT": 0.0})  # linear relaxation length everywhere
    kin = model.kinematics(Fz=FZ, Vx=VX, Vy=0.1, omega=25.0)
    u, v = 0.0, 0.0
    for _ in range(100):
        u, v = step_exact(model, kin, u, v, 1e-3)
    a = VX / float(kin.sigy)
    assert v == pytest.approx(0.1 / a * (1.0 - np.exp(-a * 0.1)), rel=1e-12)


# ------------------------------------------------------------------ C / FMU


@pytest.fixture(scope="module", params=[2, 3], ids=["fmi2", "fmi3"])
def fmu_path(request, tmp_path_factory):
    """The transient FMU, FMI 2.0 and FMI 3.0: the same model behind the same two thin wrappers, the same
    tests."""
    from mftire.fmu.export import export_fmu

    d = tmp_path_factory.mktemp("tfmu")
    return export_fmu(TIR, d / "tyre.fmu", request.param, transient=True)


@pytest.fixture(scope="module")
def fmu2_path(tmp_path_factory):
    """The FMI 2.0 transient FMU (the multi-instance host and fmpy's container FMU are FMI 2.0)."""
    from mftire.fmu.export import export_fmu

    d = tmp_path_factory.mktemp("tfmu2")
    return export_fmu(TIR, d / "tyre.fmu", 2, transient=True)


def _slave(fmu_path, name, messages=None):
    """A Co-Simulation instance (FMI 2 or 3) through mftire's small host: set, get, fmu.doStep."""
    from mftire.fmu.host import FMUTyre

    log = None if messages is None else (lambda status, cat, msg: messages.append((status, cat, msg)))
    return FMUTyre(fmu_path, "CS", instance_name=name, logger=log)


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    from mftire.fmu.transient_export import build_probe_library

    lib = ctypes.CDLL(str(build_probe_library(TIR, tmp_path_factory.mktemp("probe"))))
    lib.mt_probe_bench.restype = ctypes.c_double
    return lib


@needs_c_compiler
def test_c_and_python_derivatives_agree(model, probe):
    rng = np.random.default_rng(13)
    D = ctypes.c_double
    for _ in range(300):
        ins = dict(Fz=rng.uniform(0, 9000), Vx=rng.uniform(-30, 30) * rng.choice([1.0, 0.02, 0.0]),
                   Vy=rng.uniform(-3, 3), omega=rng.uniform(-90, 90), gamma=rng.uniform(-0.1, 0.1),
                   P=rng.uniform(2.0e5, 2.6e5), muRoad=rng.uniform(0.3, 1.2), yawRate=rng.uniform(-1, 1))  # fmt: skip
        x = rng.normal(0.0, 0.05, 2)
        dx, y = (D * 2)(), (D * 7)()
        assert probe.mt_probe_rates(111, (D * 8)(*ins.values()), (D * 2)(*x), dx, None) == 0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            py = model.derivatives(x, **ins)
            out = model.outputs(x, **ins)
        np.testing.assert_allclose(dx[:], py, rtol=1e-9, atol=1e-12)
        assert probe.mt_probe_outputs(111, (D * 8)(*ins.values()), (D * 2)(*x), y) == 0
        po = [float(out[k]) for k in ("Fx", "Fy", "Mz", "Mx", "My", "kappa_t", "alpha_t")]
        np.testing.assert_allclose(y[:], po, rtol=1e-9, atol=1e-9)


@needs_c_compiler
def test_lazy_outputs_equal_the_full_evaluation(fmu_path, probe, model):
    """The FMU computes outputs when read, only the channel groups read so far (and the zero-slip
    offsets below VXLOW only for them): every output read, in any order and subset, equals the full
    evaluation (all groups, probe library) at the same state bit for bit, and the Python model to
    1e-9, below and above VXLOW."""
    import fmpy

    md = fmpy.read_model_description(str(fmu_path))
    outputs = [v.name for v in sorted(md.modelVariables, key=lambda v: v.valueReference) if v.causality == "output"]
    assert outputs == output_names()
    s = _slave(fmu_path, "lazy")
    rng = np.random.default_rng(17)
    D = ctypes.c_double
    names = ("Fz", "Vx", "Vy", "omega", "gamma", "P", "muRoad", "yawRate")
    full = (D * len(outputs))()
    seen = 0
    for k in range(60):
        Vx = [0.0, 0.2, 0.9, 3.0, -0.5, 15.0][k % 6]  # VXLOW = 1 m/s: w > 0 for the first, third and fifth
        ins = (rng.uniform(1000, 8000), Vx, rng.uniform(-0.5, 0.5), rng.uniform(-5, 50), rng.uniform(-0.05, 0.05),
               rng.uniform(2.0e5, 2.6e5), rng.uniform(0.5, 1.1), rng.uniform(-0.3, 0.3))  # fmt: skip
        s.set(dict(zip(names, ins, strict=True)))
        s.fmu.doStep(k * 1e-3, 1e-3)
        # a growing, shuffled subset of the outputs, one GetReal each or all in one
        ask = list(rng.permutation(outputs)[: 1 + k // 3])
        got = [s.get([n])[0] for n in ask] if k % 2 else s.get(ask)
        x = s.get(["u", "v"])
        assert probe.mt_probe_all_outputs(111, (D * 8)(*ins), (D * 2)(*x), full) == 0
        ref = dict(zip(outputs, full[:], strict=True))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            py = model.outputs(x, **dict(zip(names, ins, strict=True)))
        for n, value in zip(ask, got, strict=True):
            assert value == ref[n] or (np.isnan(value) and np.isnan(ref[n])), (k, n, value, ref[n])
            assert abs(value - float(py[n])) <= 1e-9 * max(1.0, abs(value)), (k, n, value, float(py[n]))
        seen += len(ask)
    assert seen > 300
    s.close()
    # below VXLOW, each force read for the first time after the step needs its zero-slip offset then
    s = _slave(fmu_path, "first")
    ins = (4000.0, 0.2, 0.05, 0.5, 0.02, 2.2e5, 1.0, 0.1)
    s.set(dict(zip(names, ins, strict=True)))
    s.fmu.doStep(0.0, 1e-3)
    got = {n: s.get([n])[0] for n in ("Fx", "Fy", "Mz")}
    assert probe.mt_probe_all_outputs(111, (D * 8)(*ins), (D * 2)(*s.get(["u", "v"])), full) == 0
    for n, value in got.items():
        assert value == full[outputs.index(n)], n
    s.close()


@needs_c_compiler
def test_fmu_validates_and_declares_states(fmu_path):
    import fmpy
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(fmu_path)) == []
    md = fmpy.read_model_description(str(fmu_path))
    assert [d.variable.name for d in md.derivatives] == ["der(u)", "der(v)"]
    assert [d.variable.derivative.name for d in md.derivatives] == ["u", "v"]
    names = {v.name: v for v in md.modelVariables}
    for name in ("Fz", "Vx", "Vy", "omega", "gamma", "P", "muRoad", "yawRate"):
        assert names[name].causality == "input"
    assert float(names["muRoad"].start) == 1.0
    tyre = load(TIR)
    assert float(names["Fz"].start) == tyre["FNOMIN"]
    assert float(names["Vx"].start) == tyre["LONGVL"]  # the file's defaults; omega: free rolling there
    Re = float(tyre.evaluate(tyre["FNOMIN"], 0.0, 0.0, Vx=tyre["LONGVL"])["Re"])
    assert float(names["omega"].start) == pytest.approx(tyre["LONGVL"] / Re, rel=1e-9)
    for name in ("Fx", "Fy", "Mz", "Mx", "My", "kappa_t", "alpha_t", "sigmay", "Kya"):
        assert names[name].causality == "output"
    assert names["TR_CS_STEP"].causality == "parameter"


@needs_c_compiler
@pytest.mark.parametrize("fmi_type", ["ModelExchange", "CoSimulation"])
def test_fmu_lateral_step(fmu_path, model, fmi_type):
    import fmpy

    Vy = 0.02
    t = np.linspace(0.0, 0.3, 31)
    om, ref, _T = _lateral_step_reference(model, t, Vy)
    sig = np.array([(0.0, FZ, VX, Vy, om)], dtype=[("time", float), ("Fz", float), ("Vx", float), ("Vy", float),
                                                   ("omega", float)])  # fmt: skip
    kw = dict(relative_tolerance=1e-10) if fmi_type == "ModelExchange" else dict(step_size=1e-3)
    res = fmpy.simulate_fmu(str(fmu_path), fmi_type=fmi_type, stop_time=0.3, input=sig, output=["alpha_t", "Fy"],
                            output_interval=0.01, **kw)  # fmt: skip
    assert np.allclose(res["time"], t)
    assert np.max(np.abs(res["alpha_t"] - ref)) < 1e-3 * np.arctan(Vy / VX)


@needs_c_compiler
def test_two_instances_are_independent(fmu_path):
    a, b = _slave(fmu_path, "a"), _slave(fmu_path, "b")
    a.set({"Vx": 10.0, "Vy": 0.3, "omega": 25.0})
    b.set({"Vx": 10.0, "Vy": 0.0, "omega": 25.0})
    b.fmu.doStep(0.0, 1e-3)
    before = b.get(["Fy", "v"])
    for k in range(50):
        a.fmu.doStep(k * 1e-3, 1e-3)
    fa, after = a.get(["Fy", "v"]), b.get(["Fy", "v"])
    assert fa[1] > 1e-3 and abs(fa[0]) > 1000.0  # a built up its lateral deflection and force
    assert after == before and after[1] == 0.0  # b untouched
    a.close()
    b.close()


@needs_c_compiler
def test_host_modes_give_the_same_outputs(fmu2_path):
    """TransientFMUs: fmpy's container FMU, the prebound ctypes calls (step, step_values) and fmpy's wrapper
    methods give the same outputs bit for bit, each instance on its own row."""
    from mftire.fmu.transient_host import TransientFMUs, container_available

    rng = np.random.default_rng(5)
    inputs = np.column_stack([rng.uniform(2000.0, 6000.0, 4), rng.uniform(-1.0, 20.0, 4), rng.uniform(-0.5, 0.5, 4),
                              rng.uniform(-5.0, 70.0, 4)])  # fmt: skip
    inputs[0, 1] = 0.3  # below VXLOW: the low-speed damping TR_TAU_X acts
    modes = ("container", "direct", "fmpy") if container_available() else ("direct", "fmpy")
    runs = []
    for mode, start in [(m, {"TR_CS_STEP": 5e-5, "TR_TAU_X": 0.02}) for m in modes] + [("direct", None)]:
        for flat in (False, True):
            with TransientFMUs(fmu2_path, ("a", "b", "c", "d"), outputs=("Fx", "Fy", "Mz", "u", "v"), mode=mode,
                               start_values=start) as ty:  # fmt: skip
                out = []
                for k in range(20):
                    u = inputs * (1.0 + 0.01 * k)
                    if flat:
                        out.append(np.array(ty.step_values(k * 1e-3, 1e-3, u.ravel().tolist())).reshape(4, 5))
                    else:
                        out.append(ty.step(k * 1e-3, 1e-3, u).copy())
                assert all(s <= 1 for s, _, _ in ty.messages)  # warnings at most
            runs.append(np.array(out))
    for r in runs[1:-2]:
        assert np.array_equal(r, runs[0])
    assert not np.array_equal(runs[-1], runs[0])  # the start values reached the instances
    assert np.all(np.abs(runs[0][-1, :, 3:]) > 0.0)  # the deflection states moved, differently per instance
    assert len({tuple(row) for row in runs[0][-1]}) == 4


@pytest.mark.parametrize("key,value", [("TR_SAT", -0.5), ("TR_SAT", -1e-300), ("TR_CS_STEP", 0.0)])
def test_non_physical_constants_are_refused(tyre, key, value):
    """The transient constants' bounds are those of mftire.parameters.PARAMETER_LIMITS (the FMU's C check reads
    the same table): a negative TR_SAT would turn the carcass deflection against the slip."""
    with pytest.raises(MftireInputError, match=rf"transient constant {key} = .* must be >"):
        TransientTyre(tyre, constants={key: value})
    TransientTyre(tyre, constants={key: 0.0 if key == "TR_SAT" else 1e-9})  # on or above the bound: taken


@needs_c_compiler
@pytest.mark.parametrize("key,value", [("VXLOW", 0.0), ("VXLOW", -1.0), ("TR_CS_STEP", 0.0), ("TR_SAT", -0.5)])
def test_non_physical_start_values_fail_the_initialisation(fmu2_path, key, value):
    """VXLOW > 0, TR_CS_STEP > 0, TR_SAT >= 0: the bounds of mftire.parameters.PARAMETER_LIMITS (mftire.mf.spec),
    shared with the steady FMU."""
    from fmpy.fmi1 import FMICallException

    from mftire.fmu.transient_host import TransientFMUs

    with pytest.raises(FMICallException):
        TransientFMUs(fmu2_path, ("a",), outputs=("Fx",), mode="direct", start_values={key: value})


@needs_c_compiler
def test_container_mode_checks_the_step(fmu2_path, tmp_path):
    """Container mode: the container FMU validates; fixed step, steps one after the other (the container
    checks its own time)."""
    from fmpy.validation import validate_fmu

    from mftire.errors import MftireError
    from mftire.fmu.transient_host import TransientFMUs, build_container, container_available

    if not container_available():
        pytest.skip("fmpy has no container FMU here")
    path = build_container(fmu2_path, ("a", "b"), ("Fz", "Vx"), ("Fx", "Re"), {"TR_TAU_X": 0.02}, 1e-3, tmp_path)
    assert validate_fmu(str(path)) == []
    with TransientFMUs(fmu2_path, ("a", "b"), mode="container", step_size=2e-3) as ty:
        ty.step_values(0.0, 2e-3, [4000.0, 10.0, 0.0, 30.0] * 2)
        with pytest.raises(MftireError, match="fixed"):
            ty.step_values(2e-3, 1e-3, [4000.0, 10.0, 0.0, 30.0] * 2)
        with pytest.raises(MftireError, match="expected t = 0.002"):
            ty.step_values(6e-3, 2e-3, [4000.0, 10.0, 0.0, 30.0] * 2)


@needs_c_compiler
def test_cli_transient_flag_fmi3(tmp_path, capsys):
    import fmpy

    from mftire.cli import main

    rc = main(["export-fmu", str(TIR), "--transient", "--fmi-version", "3", "--output", str(tmp_path / "x.fmu")])
    assert rc == 0 and "FMI 3.0" in capsys.readouterr().out
    md = fmpy.read_model_description(str(tmp_path / "x.fmu"))
    assert md.fmiVersion == "3.0" and md.numberOfContinuousStates == 2


@needs_c_compiler
def test_vehicle_example_stop_and_hold(tmp_path, fmu2_path):
    """validation/vehicle_example.py, transient part: four FMU instances, launch, stop, hold on 20 %."""
    import importlib.util
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    spec = importlib.util.spec_from_file_location("vehicle_example", root / "validation" / "vehicle_example.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules["vehicle_example"] = mod
    spec.loader.exec_module(mod)
    png = tmp_path / "stop.png"
    res = mod.run_transient(TIR, png, fmu_path=fmu2_path)
    assert png.stat().st_size > 10_000
    sc = mod.StopAndHold()
    t = res["t"]
    still = t < sc.launch
    assert np.all(res["Fx"][still] == 0.0) and np.all(res["V"][still] == 0.0)  # standing still: no force, no creep
    assert res["V"].max() > 3.0
    assert res["drift"] < 1e-3  # parked on the 20 % slope: below 1 mm/s
    # held by the tyres: the four forces carry the slope force m·g·sin(theta)
    veh = mod.Vehicle()
    total = res["Fx"][-1].sum()
    assert total == pytest.approx(veh.m * veh.g * np.sin(np.arctan(sc.grade)), rel=1e-3)


@needs_c_compiler
def test_fmu_cs_step_equals_python_advance_with_limiter(fmu_path, model):
    """Spinning wheel at standstill: the deflection limiter acts; FMU CS steps = Python :func:`advance`."""
    from mftire.transient import advance

    messages = []
    s = _slave(fmu_path, "x", messages)
    ins = dict(Fz=FZ, Vx=0.0, Vy=0.05, omega=30.0)
    s.set(ins)
    kin = model.kinematics(**ins)
    u = v = 0.0
    for k in range(40):
        s.fmu.doStep(k * 0.01, 0.01)
        u, v = advance(model, kin, u, v, 0.01)
    fu, fv, kappa_t = s.get(["u", "v", "kappa_t"])
    s.close()
    assert u > float(kin.sigx) * model.constants["TR_KAPPA_LIM"]  # beyond the limit: the limiter acted
    assert u < 1.5 * float(kin.sigx) * model.constants["TR_KAPPA_LIM"]  # and bounded the deflection
    assert fu == pytest.approx(u, rel=1e-12) and fv == pytest.approx(v, rel=1e-12)
    assert np.isfinite(kappa_t)
    # the limit warnings of the steady-state evaluation arrive formatted (KPUMAX exceeded), each kind once in
    # these 40 steps (one message per kind per 1000 evaluations)
    kpumax = [m for _, _, m in messages if "KPUMAX" in m]
    assert len(kpumax) == 1 and len(messages) <= 3


def test_simulate_free_rolling_default_and_varying_friction(tyre):
    """omega omitted: free rolling (no longitudinal slip); muRoad as an array on t."""
    t = np.linspace(0.0, 0.6, 13)
    res = simulate(tyre, t, Fz=FZ, Vx=VX, Vy=0.2)
    assert np.all(res["kappa_t"] == 0.0)
    ss = tyre.evaluate(FZ, 0.0, np.arctan(0.2 / VX), Vx=VX)
    assert res["Fy"].iloc[-1] == pytest.approx(float(ss["Fy"]), rel=1e-6)
    assert res["Fx"].iloc[-1] == pytest.approx(float(ss["Fx"]), rel=1e-6)
    mu = np.linspace(0.5, 1.0, t.size)
    res = simulate(tyre, t, Fz=FZ, Vx=VX, Vy=0.2, muRoad=mu)
    np.testing.assert_allclose(res["mux"] / res["mux"].iloc[-1], mu, rtol=1e-12)


def test_model_extensions_refused(tmp_path):
    """[MFTIRE_EXTENSIONS] are not part of the transient model yet: a clear error, in Python and at export."""
    from mftire.extensions import SECTION
    from mftire.fmu.export import FMUExportError, export_fmu
    from mftire.iotools.tir import read_tir
    from mftire.tyre import Tyre

    params = read_tir(TIR)
    for k, v in {"EXT1_TARGET": "FX_OFFSET", "EXT1_FORM": "linear", "EXT1_VARIABLE": "sign_kappa",
                 "EXT1_C1": 0.01}.items():  # fmt: skip
        params.set(k, v, section=SECTION)
    tyre = Tyre(params, name="ext.tir")
    with pytest.raises(MftireInputError, match="MFTIRE_EXTENSIONS"):
        TransientTyre(tyre)
    with pytest.raises(FMUExportError, match="MFTIRE_EXTENSIONS"):
        export_fmu(tyre, tmp_path / "x.fmu", transient=True)


@needs_c_compiler
def test_repeated_warnings_are_rate_limited_per_step(fmu_path):
    """A wheel spinning at standstill raises KPUMAX every step: one message per 1000 steps with the count of
    the others, also with debug logging on (tools on the FMI Library always switch it on)."""
    messages = []
    s = _slave(fmu_path, "spin", messages)
    s.fmu.setDebugLogging(True, [])
    s.set({"Fz": FZ, "Vx": 0.0, "Vy": 0.05, "omega": 30.0})
    for k in range(2600):
        s.fmu.doStep(k * 0.01, 0.01)
        s.get(["Fx"])
    s.close()
    kpumax = [m for _, _, m in messages if "KPUMAX" in m]
    assert len(kpumax) in (2, 3), kpumax[:4]  # at its first step, 1000 and 2000 steps later
    assert "999 more since the last message" in kpumax[1] and "more since" not in kpumax[0]
