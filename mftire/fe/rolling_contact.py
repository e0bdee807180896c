"""Steady-state rolling-contact solution: brush (TreadSim-style) model on a flexible carcass.

Scheme (documented in docs/fe_surrogate.md):

1. Geometry from the carcass: deflection rho = Fz/Cz, free radius R_Omega, belt rolling
   radius r_b, contact half-length/width, rows and land fractions (``patch``).
2. Kinematics of the tread base in the wheel frame: belt speed Vr = omega r_b, slip
   velocity of the contact centre (Vsx, Vsy) = (Vx - Vr, Vx tan alpha) (thesis eqs 3.1, 5.4),
   camber spin Om = (1 - eps_gamma) omega sin(gamma), and the carcass twist psi_c which
   turns the base lines: the rigid slip velocity of element (x, y) is
   w = (Vsx - Om y, Vsy + Om x - Vr psi_c)  (steady ALE slip rate, thesis eq 2.39).
3. March along every row from the leading to the trailing edge (material time step
   dt = dx / Vr).  Each tread element is a Kelvin-Voigt bristle (k, c = k t_d) whose tip
   obeys the regularised, isotropic van der Steen law (eqs 2.46-2.49).  Implicit Euler with an
   elastic predictor tau_tr = k (u - dt w) - c w and a return map along the sliding direction:
   tau_tr,i = (K_i s + mu(p, s) p min(s/gamma_crit, 1)) e_i, K_i = k_i dt + c_i, solved for the
   local sliding speed s by a bracketed Newton iteration using the thesis's appendix-A slope.
   The sliding velocity entering mu(p, v) is therefore the element's own, consistent one.
4. Forces and moments by summation; the carcass state (u_c, v_c, psi_c, lateral load transfer)
   is updated from (Fx, Fy, Mz) with under-relaxation until converged (fixed-point iteration).
5. Rolling resistance: the pressure centre sits e = f_r rl ahead of the contact centre, f_r from
   the hysteresis loss parameter (carcass.rolling_resistance_coefficient); the zero-torque
   (free-rolling) state then has Fx = My/rl < 0.

All arrays are vectorised over operating points (batch) and rows; SI units.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from mftire.fe import carcass as cc
from mftire.fe import patch as pt
from mftire.fe.config import TyreConfig, check_operating_range
from mftire.fe.friction import pressure_factor, velocity_factor_and_slope, velocity_law

_MIN_BELT_SPEED = 1e-3  # Vr floor as a fraction of Vx (locked wheel: quasi-infinite dwell time)


@dataclass
class SteadyStateResult:
    """Outputs per operating point (arrays of shape (n,)); ISO/TYDEX W-axis signs."""

    Fx: np.ndarray  #: longitudinal force [N]
    Fy: np.ndarray  #: lateral force [N]
    Mz: np.ndarray  #: aligning moment [N·m]
    Mx: np.ndarray  #: overturning moment at the contact centre [N·m]
    My: np.ndarray  #: rolling-resistance moment at the contact centre [N·m]
    loaded_radius: np.ndarray  #: rl [m]
    rolling_radius: np.ndarray  #: belt (kinematic) rolling radius r_b [m]
    contact_length: np.ndarray  #: 2a [m]
    contact_width: np.ndarray  #: 2b [m]
    wheel_torque: np.ndarray  #: drive torque on the wheel needed for this state [N·m]
    slip_velocity_x: np.ndarray  #: Vsx = Vx - omega r_b [m/s]
    iterations: np.ndarray  #: carcass iterations used
    converged: np.ndarray  #: carcass iteration converged
    carcass_state: np.ndarray  #: (n, 4): u_c [m], v_c [m], psi_c [rad], lateral transfer [-]
    maps: dict[str, np.ndarray] | None = field(default=None)  #: (n, ny, nx) maps, on request


@dataclass
class _Batch:
    """Per-point constants of one batch (all arrays (n,) or (n, ny))."""

    Fz: np.ndarray
    Vx: np.ndarray
    Vr: np.ndarray
    Vsx: np.ndarray
    Vsy: np.ndarray
    spin: np.ndarray
    rl0: np.ndarray
    r_b: np.ndarray
    geom: pt.PatchGeometry
    c_sh: np.ndarray
    skew: np.ndarray
    cx: np.ndarray
    cy: np.ndarray
    cpsi: np.ndarray
    mu_s: np.ndarray
    dmu: np.ndarray
    h2: np.ndarray
    v_max: np.ndarray
    gamma_crit: np.ndarray
    lat_gain: np.ndarray


def _prepare(tyre: TyreConfig, Fz, Vx, P, omega, alpha, gamma) -> _Batch:
    rho = cc.vertical_deflection(tyre, Fz, Vx, P)
    R_om = cc.free_radius(tyre, Vx)
    rl0 = R_om - rho
    r_b = cc.belt_rolling_radius(tyre, Fz, Vx, P)
    a = pt.contact_half_length(R_om, rho, tyre.patch.q_a)
    b = pt.contact_half_width(tyre, rho)
    geom = pt.patch_geometry(tyre, a, b)
    f_r = cc.rolling_resistance_coefficient(tyre, rho, a, Vx)
    skew = pt.skew_for_offset(geom.xi, tyre.patch.pressure_exponent, f_r * rl0 / a)
    cx, cy, cpsi = cc.compliances(tyre, Fz, P)
    law = velocity_law(tyre.friction, Vx)
    Vr = np.maximum(omega * r_b, _MIN_BELT_SPEED * Vx)
    alpha_eff = alpha + tyre.carcass.plysteer
    spin = (1.0 - tyre.carcass.camber_reduction) * omega * np.sin(gamma)  # camber spin (Pacejka 2012 §3.2.2)
    return _Batch(
        Fz=Fz, Vx=Vx, Vr=Vr,
        Vsx=Vx - omega * r_b,  # longitudinal slip speed, thesis eq 5.4
        Vsy=Vx * np.tan(alpha_eff),  # lateral slip speed, thesis eq 3.1
        spin=spin, rl0=rl0, r_b=r_b, geom=geom,
        c_sh=pt.shoulder_bias(tyre, Fz, P), skew=skew, cx=cx, cy=cy, cpsi=cpsi,
        mu_s=law.mu_s, dmu=law.mu_m - law.mu_s, h2=law.h**2, v_max=law.v_max,
        gamma_crit=law.gamma_crit,
        lat_gain=-tyre.patch.camber_shift * np.sin(gamma),
    )


def _return_map(tx, ty, Kx, Ky, pmu, mu_s, dmu, h2, v_max, g_c, s0, iters, tol=0.0):
    """Local sliding speed s >= 0 of a bristle tip, for all elements of one column.

    Solves |(tau_x/(Kx s + Q), tau_y/(Ky s + Q))| = 1 with Q(s) = mu_p p mu_v(s) min(s/g_c, 1)
    (regularised law, thesis eqs 2.47-2.49) by Newton steps safeguarded by bisection inside
    the bracket [0, |tau_tr|/min(K)]; dQ/ds uses the derivative of thesis appendix A (A.4, A.11).
    An element stops once its error after an accepted Newton step is at most ``tol`` max(s, g_c):
    the error is estimated from two successive Newton steps d1, d2 as d2^3/d1^2 (quadratic
    convergence, e_k+1 ~ C e_k^2), or bounded by the step itself (``tol = 0``: every element
    runs all ``iters`` iterations).  Elements still iterating are gathered into compact arrays,
    so converged ones cost nothing more.  An element's iterates depend on its own data only,
    never on the other elements of the batch.
    Returns (s, Q, unit vector components ex, ey, mu_v), shaped like the broadcast inputs.
    """
    shape = np.broadcast_shapes(*(np.shape(v) for v in (tx, ty, Kx, Ky, pmu, mu_s, g_c, s0)))
    tx, ty, Kx, Ky, pmu, mu_s, dmu, h2, v_max, g_c, s0 = (
        np.broadcast_to(v, shape).ravel() for v in (tx, ty, Kx, Ky, pmu, mu_s, dmu, h2, v_max, g_c, s0))
    tn = np.hypot(tx, ty)
    tn_safe = np.maximum(tn, 1e-9)
    ax, ay = tx / tn_safe, ty / tn_safe
    axx, ayy = ax * ax, ay * ay

    def residual(s, pmu, mu_s, dmu, h2, v_max, g_c, Kx, Ky, axx, ayy, tn_safe):
        muv, dmuv = velocity_factor_and_slope(s, mu_s, dmu, h2, v_max)
        stick = s < g_c
        m = np.where(stick, s / g_c, 1.0)
        Q = pmu * muv * m
        dQ = pmu * (dmuv * m + np.where(stick, muv / g_c, 0.0))
        ix, iy = 1.0 / (Kx * s + Q), 1.0 / (Ky * s + Q)  # 1/D_x, 1/D_y
        ix2, iy2 = ix * ix, iy * iy
        r = 1.0 / np.sqrt(np.maximum(axx * ix2 + ayy * iy2, 1e-30))  # S^(-1/2)
        return r - tn_safe, r * r * r * (axx * (Kx + dQ) * ix2 * ix + ayy * (Ky + dQ) * iy2 * iy)

    # the law has a kink at gamma_crit (eq 2.47): pick the smooth branch holding the root first
    hi = tn_safe / np.minimum(Kx, Ky)
    work = (pmu, mu_s, dmu, h2, v_max, g_c, Kx, Ky, axx, ayy, tn_safe)
    r_c, _ = residual(np.minimum(g_c, hi), *work)
    in_stick = r_c >= 0.0
    lo = np.where(in_stick, 0.0, g_c)
    hi = np.where(in_stick, np.minimum(g_c, hi), hi)
    # isotropic closed-form start with mu frozen at the upstream sliding speed
    muv0, _ = velocity_factor_and_slope(s0, mu_s, dmu, h2, v_max)
    K = 0.5 * (Kx + Ky)
    q0 = pmu * muv0
    s = np.where(in_stick, tn / (K + q0 / g_c), (tn - q0) / K)
    s = np.where((s > lo) & (s < hi), s, 0.5 * (lo + hi))
    out = s  # final iterates, written as elements converge
    idx = np.arange(s.size)  # position in ``out`` of each working element
    alive = np.ones(s.size, dtype=bool)  # working elements still iterating
    d1 = np.full(s.size, np.inf)  # last Newton step (inf: the last step was a bisection)
    for _ in range(iters):
        res, dres = residual(s, *work)
        lo = np.where(res < 0.0, s, lo)
        hi = np.where(res > 0.0, s, hi)
        s_new = s - res / np.maximum(dres, 1e-30)
        newton = (s_new >= lo) & (s_new <= hi)
        s_next = np.where(newton, s_new, 0.5 * (lo + hi))
        if tol > 0.0:
            d2 = np.where(newton, np.abs(s_next - s), np.inf)
            pair = newton & (d1 > 0.0) & (d1 < np.inf)  # two Newton steps in a row
            err = np.where(pair, d2 * (d2 / np.where(pair, d1, 1.0)) ** 2, d2)  # quadratic: e ~ d2^3 / d1^2
            err = np.minimum(err, d2)
            done = alive & (err <= tol * np.maximum(s_next, work[5]))
            out[idx[done]] = s_next[done]  # frozen at its converged iterate
            alive &= ~done
            d1 = d2
        s = np.where(alive, s_next, s)
        if tol > 0.0 and alive.sum() < 0.75 * alive.size:  # gather the elements still iterating
            if not alive.any():
                break
            idx, s, lo, hi, d1 = idx[alive], s[alive], lo[alive], hi[alive], d1[alive]
            work = tuple(a[alive] for a in work)
            alive = alive[alive]
    out[idx[alive]] = s[alive]
    s = out
    muv, _ = velocity_factor_and_slope(s, mu_s, dmu, h2, v_max)
    Q = pmu * muv * np.minimum(s / g_c, 1.0)
    Dx, Dy = Kx * s + Q, Ky * s + Q
    ex, ey = tx / np.maximum(Dx, 1e-30), ty / np.maximum(Dy, 1e-30)
    norm = np.maximum(np.hypot(ex, ey), 1e-30)
    ex, ey = np.where(tn > 0, ex / norm, 0.0), np.where(tn > 0, ey / norm, 0.0)
    return tuple(v.reshape(shape) for v in (s, Q, ex, ey, muv))


def _brush_pass(tyre: TyreConfig, B: _Batch, idx: np.ndarray, state: np.ndarray, want_maps: bool):
    """One sweep over the contact patch for the points ``idx`` with a frozen carcass state."""
    t, f, g = tyre.tread, tyre.friction, tyre.grid
    geom = B.geom
    uc, vc, psi, lam_fy = state[:, 0], state[:, 1], state[:, 2], state[:, 3]
    a = geom.a[idx]
    sub = pt.PatchGeometry(a=a, b=geom.b[idx], y=geom.y[idx], dy=geom.dy[idx], land=geom.land[idx],
                           eta=geom.eta[idx], xi=geom.xi)
    lam = lam_fy + B.lat_gain[idx]
    c_sh = B.c_sh[idx]
    a_row = pt.row_half_lengths(tyre, sub, c_sh, lam)
    p_row, gshape, area = pt.pressure_field(tyre, B.Fz[idx], sub, a_row, c_sh, lam, B.skew[idx])
    nx = geom.xi.size
    dx = 2.0 * a_row / nx
    Vr = B.Vr[idx][:, None]
    dt = dx / Vr
    Kx = t.kx * (dt + t.damping_time)
    Ky = t.ky * (dt + t.damping_time)
    cdx, cdy = t.kx * t.damping_time, t.ky * t.damping_time
    y = sub.y
    Vsx, Vsy, spin = B.Vsx[idx][:, None], B.Vsy[idx][:, None], B.spin[idx][:, None]
    mu_s, dmu, h2 = B.mu_s[idx][:, None], B.dmu[idx][:, None], B.h2[idx][:, None]
    v_max, g_c = B.v_max[idx][:, None], B.gamma_crit[idx][:, None]
    psi_c = psi[:, None]
    wx = Vsx - spin * y  # rigid slip velocity, x (thesis eq 2.39, steady state)
    ux = np.zeros_like(y)
    uy = np.zeros_like(y)
    s_prev = np.zeros_like(y)
    Fx = np.zeros(idx.size)
    Fy = np.zeros(idx.size)
    Mz = np.zeros(idx.size)
    Mx = np.zeros(idx.size)
    My = np.zeros(idx.size)
    Y0 = y + vc[:, None]
    maps = None
    if want_maps:
        shape = (idx.size, y.shape[1], nx)
        maps = {k: np.zeros(shape) for k in ("x", "y", "pressure", "mu", "sliding_velocity",
                                             "friction_power", "shear_x", "shear_y")}
    for i in range(nx):
        x = a_row * geom.xi[i]
        p = p_row * gshape[:, i][:, None]
        wy = Vsy + spin * x - Vr * psi_c  # lateral rigid slip incl. carcass twist
        ux_tr = ux - dt * wx
        uy_tr = uy - dt * wy
        tx = t.kx * ux_tr - cdx * wx  # Kelvin-Voigt elastic predictor
        ty = t.ky * uy_tr - cdy * wy
        mup = pressure_factor(p, f.p0, f.k, f.plimit)
        pmu = mup * p
        s, Q, ex, ey, muv = _return_map(tx, ty, Kx, Ky, pmu, mu_s, dmu, h2, v_max, g_c,
                                       np.maximum(s_prev, 1e-6 * g_c), g.newton_iter,
                                       g.newton_tol)
        taux, tauy = Q * ex, Q * ey
        ux = ux_tr - dt * s * ex
        uy = uy_tr - dt * s * ey
        s_prev = s
        fxa, fya, pa = taux * area, tauy * area, p * area
        X = x + uc[:, None]
        Y = Y0 + psi_c * x
        Fx += fxa.sum(axis=1)
        Fy += fya.sum(axis=1)
        Mz += (X * fya - Y * fxa).sum(axis=1)
        Mx += (Y * pa).sum(axis=1)
        My -= (X * pa).sum(axis=1)
        if maps is not None:
            maps["x"][:, :, i] = X
            maps["y"][:, :, i] = Y
            maps["pressure"][:, :, i] = p * (area > 0)
            maps["mu"][:, :, i] = np.where(area > 0, mup * muv, 0.0)
            maps["sliding_velocity"][:, :, i] = np.where(area > 0, s, 0.0)
            maps["friction_power"][:, :, i] = np.where(area > 0, Q * s, 0.0)  # tau_eqv gamma_eqv
            maps["shear_x"][:, :, i] = np.where(area > 0, taux, 0.0)
            maps["shear_y"][:, :, i] = np.where(area > 0, tauy, 0.0)
    return Fx, Fy, Mz, Mx, My, maps


def solve(
    tyre: TyreConfig,
    Fz: ArrayLike,
    Vx: ArrayLike,
    P: ArrayLike,
    omega: ArrayLike,
    alpha: ArrayLike = 0.0,
    gamma: ArrayLike = 0.0,
    *,
    maps: bool = False,
) -> SteadyStateResult:
    """Steady-state forces of the rolling tyre at prescribed wheel speed.

    Parameters (broadcast to a common 1-D batch): Fz vertical load [N] (> 0), Vx longitudinal
    speed of the wheel centre [m/s], P inflation pressure [Pa], omega wheel spin [rad/s],
    alpha slip angle [rad] (tan alpha = Vsy/Vx, thesis eq 3.1), gamma camber [rad].
    ``maps=True`` adds (n, ny, nx) maps of pressure, local mu, sliding velocity and friction
    power per area (thesis Fig. 6.16).
    """
    arrs = np.broadcast_arrays(*(np.atleast_1d(np.asarray(v, dtype=float)) for v in
                                 (Fz, Vx, P, omega, alpha, gamma)))
    Fz, Vx, P, omega, alpha, gamma = (np.ravel(a).copy() for a in arrs)
    check_operating_range(tyre, Fz, Vx, P)
    for name, arr in (("omega", omega), ("alpha", alpha), ("gamma", gamma)):
        if not np.all(np.isfinite(arr)):
            from mftire.errors import MftireInputError

            raise MftireInputError(f"operating point {name} contains NaN or inf")
    B = _prepare(tyre, Fz, Vx, P, np.maximum(omega, 0.0), alpha, gamma)
    n = Fz.size
    g = tyre.grid
    state = np.zeros((n, 4))
    out = np.zeros((n, 5))
    iters = np.zeros(n, dtype=int)
    converged = np.zeros(n, dtype=bool)
    active = np.arange(n)
    scale = np.array([1.0, 1.0, 1.0, 0.01])  # tolerance scale of (u_c, v_c, psi_c, lambda)
    beta = g.relaxation
    for it in range(g.carcass_maxiter):
        Fx, Fy, Mz, Mx, My, _ = _brush_pass(tyre, B, active, state[active], False)
        out[active] = np.column_stack([Fx, Fy, Mz, Mx, My])
        target = np.column_stack([
            Fx / B.cx[active],  # u_c = Fx / Cx
            Fy / B.cy[active],  # v_c = Fy / Cy
            Mz / B.cpsi[active],  # psi_c = Mz / Cpsi (yaw compliance)
            # belt roll: the pressure centre moves back toward the wheel plane by a fraction
            # 'lateral_shift' of the carcass lateral deflection (centroid of (1 + lam eta) is lam b/3)
            -3.0 * tyre.patch.lateral_shift * (Fy / B.cy[active]) / B.geom.b[active],
        ])
        delta = target - state[active]
        iters[active] = it + 1
        done = np.all(np.abs(delta) <= g.carcass_tol / scale, axis=1)
        state[active] += beta * delta
        converged[active[done]] = True
        active = active[~done]
        if active.size == 0:
            break
    mp = None
    if maps:
        Fx, Fy, Mz, Mx, My, mp = _brush_pass(tyre, B, np.arange(n), state, True)
        out = np.column_stack([Fx, Fy, Mz, Mx, My])
    Fx, Fy, Mz, Mx, My = out.T
    rl = cc.loaded_radius(tyre, Fz, Vx, P, Fy)
    return SteadyStateResult(
        Fx=Fx, Fy=Fy, Mz=Mz, Mx=Mx, My=My,
        loaded_radius=rl, rolling_radius=B.r_b,
        contact_length=2.0 * B.geom.a, contact_width=2.0 * B.geom.b,
        wheel_torque=rl * Fx - My,  # axle torque balance: T + (-rl Fx + My) = 0
        slip_velocity_x=B.Vsx, iterations=iters, converged=converged,
        carcass_state=state, maps=mp,
    )
