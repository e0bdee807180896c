/*
 * mf_transient.c -- the transient slip model of mftire/transient.py in C99.
 * Each line mirrors the Python; see mf_transient.h and docs/transient.md.
 */
#include <math.h>
#include <stddef.h>

#include "mf_transient.h"

static double nan_to(double x, double fill) { return isnan(x) ? fill : x; }

/* Slip at which the carcass deflection saturates: force mu*Fz over the slip stiffness |K| (0 where not positive
 * and finite: no saturation). */
static double sat_slip(double mu, double Fz, double K)
{
    double q = fabs(mu) * Fz / fabs(K);
    return (isfinite(q) && q > 0.0) ? q : 0.0;
}

/* Sliding force over peak force: the Magic Formula's asymptote D*sin(pi/2*C) over D (Pacejka 2012 §4.3.2), for
 * 0 < C < 2; 1 otherwise. */
static double sliding(double C)
{
    const double PI = 3.14159265358979323846;
    return (C > 0.0 && C < 2.0) ? fabs(sin(0.5 * PI * C)) : 1.0;
}

/* 1/max(sech^2(q/qs), smin): how much faster than the linear lag the slip state q relaxes where the
 * characteristic (slip stiffness K, peak mu*Fz) flattens; 1 where qs = 0.  sech^2 = 4t/(1+t)^2 with
 * t = exp(-2|x|) (no overflow). */
static double slope_factor(double q, double qs, double smin)
{
    double t, s;
    if (!(qs > 0.0) || q == 0.0) return 1.0 / (1.0 > smin ? 1.0 : smin); /* sech^2(0) = 1 */
    t = exp(-2.0 * fabs(q / qs));
    s = 4.0 * t / ((1.0 + t) * (1.0 + t));
    return 1.0 / (s > smin ? s : smin);
}

void mt_kinematics(const MFParams *p, int use_mode, const MTInputs *in, unsigned offsets, MTKin *k,
                   unsigned long *warnings)
{
    const double PI = 3.14159265358979323846;
    double Fz = nan_to(in->Fz, 0.0), Vx = nan_to(in->Vx, 0.0), Vy = nan_to(in->Vy, 0.0);
    double omega = nan_to(in->omega, 0.0), yaw = nan_to(in->yawRate, 0.0);
    double vxlow = p->VXLOW, absVx = fabs(Vx), vfloor, Vev, r, q;
    unsigned want = MF_WANT_RELAX; /* sigma; mu and K for the saturation slips */
    unsigned long w;
    int i;
    r = absVx / vxlow < 1.0 ? absVx / vxlow : 1.0;
    /* low-speed weight (cosine, as MFeval's VXLOW reduction); from VXLOW on exactly 0.5 * (1 + cos(PI)) = 0 */
    k->w = r < 1.0 ? 0.5 * (1.0 + cos(PI * r)) : 0.0;
    /* the rolling offsets are needed below VXLOW only (w > 0), and only for the groups asked for */
    if (k->w > 0.0) want |= offsets & MT_OFFSETS;
    k->offsets = k->w > 0.0 ? offsets & MT_OFFSETS : MT_OFFSETS;
    /* evaluation speed: forward, never below VXLOW; the floor is the next double above VXLOW so that the
     * Magic Formula stays out of its low-speed mode (|Vx| <= VXLOW, whose factors are all 1 at VXLOW) */
    vfloor = nextafter(vxlow, INFINITY);
    Vev = absVx > vfloor ? absVx : vfloor;
    k->ev.Fz = Fz;
    k->ev.kappa = 0.0;
    k->ev.alpha = 0.0;
    k->ev.gamma = nan_to(in->gamma, 0.0);
    k->ev.phit = -yaw / sqrt(Vev * Vev + Vy * Vy); /* turn slip phi_t = -psi_dot/V (Pacejka 2012 eq 4.75) */
    k->ev.Vx = Vev;
    k->ev.P = in->P;
    k->ev.omega = omega == 0.0 ? 1e-300 : omega; /* a true 0: not "estimate omega" */
    k->ev.muRoad = nan_to(in->muRoad, 1.0);
    for (i = 0; i < MF_MAX_DATA; i++) k->ev.data[i] = in->data[i];
    k->zero.Fx = k->zero.Fy = k->zero.Mz = 0.0; /* offsets not evaluated: 0 (w = 0, or not used) */
    w = mf_evaluate_unchecked(p, use_mode, &k->ev, want, &k->zero);
    if (warnings) *warnings |= w;
    k->Vx = Vx;
    k->Vsx = Vx - omega * k->zero.Re; /* longitudinal slip velocity (Pacejka 2012 eq 2.5 / 4.E5) */
    k->Vsy = Vy;
    k->sigx = k->zero.sigmax > p->TR_SIGMA_MIN ? k->zero.sigmax : p->TR_SIGMA_MIN; /* Besselink 2010 eq 19 */
    k->sigy = k->zero.sigmay > p->TR_SIGMA_MIN ? k->zero.sigmay : p->TR_SIGMA_MIN; /* Besselink 2010 eq 19 */
    /* sliding force D*|sin(pi/2*C)| (the asymptote of the Magic Formula, Pacejka 2012 §4.3.2) over the slip
     * stiffness; C = PCX1*LCX (eq 4.E11), PCY1*LCY (eq 4.E21) */
    k->slx = p->TR_SAT * sat_slip(k->zero.mux * sliding(p->PCX1 * p->LCX), k->zero.Fz, k->zero.Kxk);
    k->sly = p->TR_SAT * sat_slip(k->zero.muy * sliding(p->PCY1 * p->LCY), k->zero.Fz, k->zero.Kya);
    q = Vx / vxlow;
    q = q > 1.0 ? 1.0 : (q < -1.0 ? -1.0 : q);
    /* smooth sign of the rolling direction; sin(+-PI/2) is exactly +-1 in double */
    k->My_sign = q == 1.0 ? 1.0 : (q == -1.0 ? -1.0 : sin(0.5 * PI * q));
}

/* Carcass deflection rates dc = (du_c/dt, dv_c/dt) (the linear lag with the deflection limiter), the rates
 * A = (A_x, A_y) [m/s] and the slope factors r = (r_x, r_y): du/dt = r_x*dc_x (mftire.transient lag()). */
static void lag(const MFParams *p, const MTKin *k, const double x[2], double dc[2], double A[2], double r[2])
{
    double gx = fabs(x[0]) / (k->sigx * p->TR_KAPPA_LIM) - 1.0, gy = fabs(x[1]) / (k->sigy * p->TR_TANALPHA_LIM) - 1.0;
    gx = gx > 0.0 ? gx : 0.0; /* deflection limiter */
    gy = gy > 0.0 ? gy : 0.0;
    A[0] = fabs(k->Vx) + p->TR_LIM_GAIN * fabs(k->Vsx) * gx * gx;
    A[1] = fabs(k->Vx) + p->TR_LIM_GAIN * fabs(k->Vsy) * gy * gy;
    dc[0] = -k->Vsx - A[0] * (x[0] / k->sigx); /* Pacejka 2012 §7.2.1: du/dt + |Vx|/sigma_kappa*u = -Vsx */
    dc[1] = k->Vsy - A[1] * (x[1] / k->sigy);  /* Pacejka 2012 §7.2.1: dv/dt + |Vx|/sigma_alpha*v = Vsy (ISO sign) */
    r[0] = slope_factor(x[0] / k->sigx, k->slx, p->TR_SIGMA_MIN / k->sigx);
    r[1] = slope_factor(x[1] / k->sigy, k->sly, p->TR_SIGMA_MIN / k->sigy);
}

void mt_rates(const MFParams *p, const MTKin *k, const double x[2], double dx[2])
{
    double dc[2], A[2], r[2];
    lag(p, k, x, dc, A, r);
    /* slope of the characteristic: local relaxation length sigma*sech^2 (Pacejka 2012 §7.2.2/§7.3) */
    dx[0] = r[0] * dc[0];
    dx[1] = r[1] * dc[1];
}

void mt_outputs(const MFParams *p, int use_mode, const MTKin *k, const double x[2], unsigned want,
                MTOutputs *out, unsigned long *warnings)
{
    double dx[2], A[2], r[2];
    MFInputs ev = k->ev;
    unsigned long w;
    lag(p, k, x, dx, A, r); /* damping on the carcass deflection rate */
    out->kappa_t = (x[0] + k->w * p->TR_TAU_X * dx[0]) / k->sigx;    /* low-speed damping (§7.3) */
    out->alpha_t = atan((x[1] + k->w * p->TR_TAU_Y * dx[1]) / k->sigy); /* tan alpha' = v/sigma_alpha */
    ev.kappa = out->kappa_t;
    ev.alpha = out->alpha_t;
    w = mf_evaluate_unchecked(p, use_mode, &ev, want, &out->ss);
    if (warnings) *warnings |= w;
    /* rolling offsets fade out below VXLOW (an output is valid only when its group is wanted) */
    if (want & MF_WANT_FX) out->ss.Fx -= k->w * k->zero.Fx;
    if (want & MF_WANT_FY) out->ss.Fy -= k->w * k->zero.Fy;
    if (want & MF_WANT_MZ) out->ss.Mz -= k->w * k->zero.Mz;
    if (want & MF_WANT_MY) out->ss.My *= k->My_sign; /* rolling resistance opposes the rolling direction */
    /* last line: no output is ever non-finite (fields of groups not wanted hold earlier, guarded values) */
    out->nonfinite = 0;
    {
        double *o = (double *)&out->ss;
        size_t i, n = sizeof out->ss / sizeof(double);
        for (i = 0; i < n; i++)
            if (!isfinite(o[i])) {
                o[i] = 0.0;
                out->nonfinite++;
            }
        if (!isfinite(out->kappa_t)) { out->kappa_t = 0.0; out->nonfinite++; }
        if (!isfinite(out->alpha_t)) { out->alpha_t = 0.0; out->nonfinite++; }
    }
}

/*
 * Equilibrium of ds/dt = r*(f - A(s)*s/sig) with A(s) = |Vx| + G*|Vs|*max(0, |s|/L - 1)^2 (L = sig*lim): the
 * state the held inputs drive s to, monotonically (one-dimensional, A increasing in |s|).  Returns 0 when
 * there is none (no leak: |Vx| = 0 and G*|Vs| = 0, or f = 0 and |Vx| = 0).  Beyond the limit, bisection on
 * [L, L*(1 + 1/sqrt(G*lim))] (60 halvings: to the last bits).
 */
static int equilibrium(double f, double sig, double lim, double absVx, double Vs, double G, double *s_eq)
{
    double L = sig * lim, c = fabs(f) * sig, lo, hi, mid, gm;
    int i;
    if (f == 0.0) {
        *s_eq = 0.0;
        return absVx > 0.0 || G * fabs(Vs) > 0.0;
    }
    if (absVx * L >= c) { /* within the limit: the linear lag's steady state */
        *s_eq = f * sig / absVx;
        return 1;
    }
    if (!(G * fabs(Vs) > 0.0) || !(lim > 0.0)) return 0;
    lo = L;
    hi = L * (1.0 + 1.0 / sqrt(G * lim)); /* G*|Vs|*(hi/L-1)^2*hi >= |Vs|*sig >= c (|f| <= |Vs|) */
    if (absVx > 0.0 && c / absVx < hi) hi = c / absVx;
    for (i = 0; i < 60; i++) {
        mid = 0.5 * (lo + hi);
        gm = mid / L - 1.0;
        if ((absVx + G * fabs(Vs) * gm * gm) * mid < c) lo = mid;
        else hi = mid;
    }
    *s_eq = f > 0.0 ? 0.5 * (lo + hi) : -0.5 * (lo + hi);
    return 1;
}

/* Exact solution over h of ds/dt = r*(f - A*s/sig) with r, A, f frozen (exponential Euler), not carried past
 * the equilibrium s_eq of the unfrozen equation (the true solution never crosses it): stable for any h. */
static double step1(double s, double sig, double A, double r, double f, double h, int has_eq, double s_eq)
{
    double a = r * A / sig, ah = a * h, phi, y;
    phi = ah < 1e-12 ? h : -expm1(-ah) / a;
    y = s * exp(-ah) + r * f * phi;
    if (has_eq && (y - s_eq) * (s - s_eq) < 0.0) y = s_eq;
    return y;
}

/* The step of mt_step with the rates A and slope factors r of lag() at x given. */
static void step_lag(const MFParams *p, const MTKin *k, double x[2], double h, const double A[2], const double r[2])
{
    double u, ex, ey;
    int hx, hy;
    hx = equilibrium(-k->Vsx, k->sigx, p->TR_KAPPA_LIM, fabs(k->Vx), k->Vsx, p->TR_LIM_GAIN, &ex);
    hy = equilibrium(k->Vsy, k->sigy, p->TR_TANALPHA_LIM, fabs(k->Vx), k->Vsy, p->TR_LIM_GAIN, &ey);
    u = step1(x[0], k->sigx, A[0], r[0], -k->Vsx, h, hx, ex);
    x[1] = step1(x[1], k->sigy, A[1], r[1], k->Vsy, h, hy, ey);
    x[0] = u;
}

void mt_step(const MFParams *p, const MTKin *k, double x[2], double h)
{
    double dc[2], A[2], r[2];
    lag(p, k, x, dc, A, r);
    step_lag(p, k, x, h, A, r);
}

/* Does the slope factor stay within MT_CS_LINEAR_TOL along the monotone path from s0 to s1?  r depends on
 * |s| only and is smallest, 1, at 0: a path through 0 includes r = 1. */
static int r_flat(double s0, double r0, double s1, double sig, double qs, double smin)
{
    double r1 = slope_factor(s1 / sig, qs, smin), lo, hi;
    lo = s0 * s1 > 0.0 ? (r0 < r1 ? r0 : r1) : slope_factor(0.0, qs, smin);
    hi = r0 > r1 ? r0 : r1;
    return hi - lo <= MT_CS_LINEAR_TOL * lo;
}

void mt_advance(const MFParams *p, const MTKin *k, double x[2], double H)
{
    double h, y[2], smx, smy, dc[2], A[2], r0[2];
    long n, i;
    if (!(H > 0.0)) return;
    lag(p, k, x, dc, A, r0);
    y[0] = x[0];
    y[1] = x[1];
    step_lag(p, k, y, H, A, r0); /* = mt_step(p, k, y, H) */
    /* the frozen step moves each state monotonically from x to y: the limiter is idle over the step when
     * both ends are within the limit */
    if (fabs(x[0]) <= k->sigx * p->TR_KAPPA_LIM && fabs(y[0]) <= k->sigx * p->TR_KAPPA_LIM &&
        fabs(x[1]) <= k->sigy * p->TR_TANALPHA_LIM && fabs(y[1]) <= k->sigy * p->TR_TANALPHA_LIM) {
        smx = p->TR_SIGMA_MIN / k->sigx;
        smy = p->TR_SIGMA_MIN / k->sigy;
        if (r_flat(x[0], r0[0], y[0], k->sigx, k->slx, smx) && r_flat(x[1], r0[1], y[1], k->sigy, k->sly, smy)) {
            if (isfinite(y[0]) && isfinite(y[1])) { /* one exponential step: exact for the linear lag */
                x[0] = y[0];
                x[1] = y[1];
            }
            return;
        }
    }
    n = (long)ceil(H / p->TR_CS_STEP - 1e-9);
    if (n < 1) n = 1;
    h = H / (double)n;
    y[0] = x[0];
    y[1] = x[1];
    for (i = 0; i < n; i++) mt_step(p, k, y, h);
    if (isfinite(y[0]) && isfinite(y[1])) {
        x[0] = y[0];
        x[1] = y[1];
    }
}

/* Physical bounds of the inputs (mftire.transient.INPUT_BOUNDS); Fz and P: factors of FZMAX and PRESMAX. */
static const double MT_LO[MT_N_INPUTS + 2] = {-HUGE_VAL, -200.0, -200.0, -2000.0, -1.55, -HUGE_VAL, 1e-3, -100.0,
                                              -100.0, -100.0};
static const double MT_HI[MT_N_INPUTS + 2] = {3.0, 200.0, 200.0, 2000.0, 1.55, 3.0, 10.0, 100.0, 300.0, 300.0};
static const char *const MT_INPUT_NAMES[MT_N_INPUTS + 2] = {"Fz", "Vx", "Vy", "omega", "gamma", "P", "muRoad", "yawRate",
                                                            "T_ambient", "T_road"};

static const size_t MT_INPUT_OFFSETS[MT_N_INPUTS + 2] = {
    offsetof(MTInputs, Fz), offsetof(MTInputs, Vx), offsetof(MTInputs, Vy), offsetof(MTInputs, omega),
    offsetof(MTInputs, gamma), offsetof(MTInputs, P), offsetof(MTInputs, muRoad), offsetof(MTInputs, yawRate),
    offsetof(MTInputs, T_ambient), offsetof(MTInputs, T_road)};

const char *mt_input_name(unsigned i) { return i < MT_N_GUARDED ? MT_INPUT_NAMES[i] : "?"; }

unsigned mt_guard_inputs(const MFParams *p, MTInputs *in, MTInputs *held)
{
    unsigned i, bad = 0;
    for (i = 0; i < MT_N_GUARDED; i++) {
        double *x = (double *)((char *)in + MT_INPUT_OFFSETS[i]), *g = (double *)((char *)held + MT_INPUT_OFFSETS[i]);
        double lo = MT_LO[i], hi = MT_HI[i];
        if (i == 0) hi *= p->FZMAX > 0.0 ? p->FZMAX : p->FNOMIN;
        if (i == 5) hi *= p->PRESMAX > 0.0 ? p->PRESMAX : p->INFLPRES;
        if (fabs(*x) < 1e-30) *x = 0.0 * *x; /* tiny and subnormal: 0 (1/x would overflow; P = 0: INFLPRES) */
        if (!isfinite(*x)) {
            *x = *g; /* last good value */
            bad |= 1u << i;
        } else if (*x < lo || *x > hi) {
            *x = *x < lo ? lo : hi;
            bad |= 1u << i;
        }
        *g = *x;
    }
    return bad;
}

#if MT_THERMAL
/* ------------------------------------------------------------------ the thermal block (mftire.thermal.heat) */

void mt_thermal_inputs(const MFParams *p, const double T[3], MTInputs *in, double *P_hot)
{
    double cold = in->P > 0.0 ? in->P : p->INFLPRES; /* NaN > 0 is false: INFLPRES, the evaluator's rule */
    if (p->TH_PRESSURE != 0.0) {
        /* gas law on absolute pressures (Gay-Lussac; Harsh & Shyrokau 2019 eq 9): heat.hot_pressure */
        *P_hot = (cold + p->TH_ATMOSPHERE) * (T[2] + MT_KELVIN) / (p->TH_COLD_TEMPERATURE + MT_KELVIN) -
                 p->TH_ATMOSPHERE;
        in->P = *P_hot;
    } else {
        *P_hot = cold;
    }
#if MT_N_DATA_NODES > 0
    {
        static const int nodes[MT_N_DATA_NODES] = MT_DATA_NODES; /* the node each law variable reads */
        int i;
        for (i = 0; i < MT_N_DATA_NODES; i++) in->data[i] = T[nodes[i]];
    }
#endif
}

void mt_thermal_heat(const MFParams *p, const MTKin *k, const MTOutputs *o, double q[3])
{
    double Vx = k->Vx, Fz = k->ev.Fz, Fx = o->ss.Fx, Fy = o->ss.Fy, floor = 0.1 * p->FNOMIN;
    double vsx = -o->kappa_t * Vx, vsy = Vx * tan(o->alpha_t); /* slip velocities (Pacejka 2012 eqs 2.10-2.12) */
    /* sliding friction power |Fx*Vsx| + |Fy*Vsy| (Harsh & Shyrokau 2019 eq 3), its share into the surface */
    q[0] = p->TH_SLIP_SHARE * (fabs(Fx * vsx) + fabs(Fy * vsy));
    /* rolling loss c*Fz*|Vx| (Pacejka 2012 eq 4.E70, QSY1 term) + hysteresis c*|Vx|*(Fx^2+Fy^2)/max(Fz, 0.1*Fz0) */
    q[1] = p->TH_ROLL_LOSS * (Fz > 0.0 ? Fz : 0.0) * fabs(Vx) +
           p->TH_HYSTERESIS * fabs(Vx) * (Fx * Fx + Fy * Fy) / (Fz > floor ? Fz : floor);
    /* convection h0 + h1*|Vx|^0.8 (Incropera & DeWitt eq 7.38) */
    q[2] = p->TH_H_AIR0 + p->TH_H_AIR1 * pow(fabs(Vx), 0.8);
}

void mt_thermal_rates(const MFParams *p, const double q[3], double T_amb, double T_road, const double T[3],
                      double dT[3])
{
    /* lumped capacitance, conduction Q = G*dT (Incropera & DeWitt §5.1, eqs 3.6, 3.19): heat.node_rates */
    double q_sb = p->TH_G_SURFACE_BULK * (T[0] - T[1]), q_bg = p->TH_G_BULK_GAS * (T[1] - T[2]);
    dT[0] = (q[0] - q_sb - q[2] * (T[0] - T_amb) - p->TH_G_ROAD * (T[0] - T_road)) / p->TH_CAP_SURFACE;
    dT[1] = (q[1] + q_sb - q_bg - p->TH_G_BULK_AMBIENT * (T[1] - T_amb)) / p->TH_CAP_BULK;
    dT[2] = q_bg / p->TH_CAP_GAS;
}

void mt_thermal_step(const MFParams *p, const double q[3], double T_amb, double T_road, double T[3], double h)
{
    /* (C/h + K) T+ = C/h T + q + sinks, tridiagonal; each row's excess of the diagonal over its off-diagonal
       conductances is carried as a sum of positive terms, never a difference (GTH variant of the Thomas
       algorithm): heat.implicit_step */
    double cs, cb, cg, g_sb, g_bg, g_ba, g_road, s1, d1, r1, s2, d2, r2, s3, r3, x1, x2, x3;
    if (!(h > 0.0)) return;
    cs = p->TH_CAP_SURFACE / h;
    cb = p->TH_CAP_BULK / h;
    cg = p->TH_CAP_GAS / h;
    g_sb = p->TH_G_SURFACE_BULK;
    g_bg = p->TH_G_BULK_GAS;
    g_ba = p->TH_G_BULK_AMBIENT;
    g_road = p->TH_G_ROAD;
    s1 = cs + q[2] + g_road;
    d1 = s1 + g_sb;
    r1 = cs * T[0] + q[0] + q[2] * T_amb + g_road * T_road;
    s2 = cb + g_ba + g_sb * s1 / d1;
    d2 = s2 + g_bg;
    r2 = cb * T[1] + q[1] + g_ba * T_amb + g_sb / d1 * r1;
    s3 = cg + g_bg * s2 / d2;
    r3 = cg * T[2] + g_bg / d2 * r2;
    x3 = r3 / s3;
    x2 = (r2 + g_bg * x3) / d2;
    x1 = (r1 + g_sb * x2) / d1;
    if (isfinite(x1) && isfinite(x2) && isfinite(x3)) {
        T[0] = x1;
        T[1] = x2;
        T[2] = x3;
    }
}
#endif /* MT_THERMAL */
