/*
 * mf_transient.c -- the transient slip model of mftire/transient.py in C99.
 * Each line mirrors the Python; see mf_transient.h and docs/transient.md.
 */
#include <math.h>

#include "mf_transient.h"

static double nan_to(double x, double fill) { return isnan(x) ? fill : x; }

int mt_kinematics(const MFParams *p, int use_mode, const MTInputs *in, unsigned offsets, MTKin *k,
                  mf_warning_fn warn, void *ctx)
{
    const double PI = 3.14159265358979323846;
    double Fz = nan_to(in->Fz, 0.0), Vx = nan_to(in->Vx, 0.0), Vy = nan_to(in->Vy, 0.0);
    double omega = nan_to(in->omega, 0.0), yaw = nan_to(in->yawRate, 0.0);
    double vxlow = p->VXLOW, absVx = fabs(Vx), vfloor, Vev, r, q;
    unsigned want = MF_WANT_RELAX;
    int rc, i;
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
    rc = mf_evaluate_want(p, use_mode, &k->ev, want, &k->zero, warn, ctx);
    if (rc != MF_OK) return rc;
    k->Vx = Vx;
    k->Vsx = Vx - omega * k->zero.Re; /* longitudinal slip velocity (Pacejka 2012 eq 2.5 / 4.E5) */
    k->Vsy = Vy;
    k->sigx = k->zero.sigmax > p->TR_SIGMA_MIN ? k->zero.sigmax : p->TR_SIGMA_MIN; /* Besselink 2010 eq 19 */
    k->sigy = k->zero.sigmay > p->TR_SIGMA_MIN ? k->zero.sigmay : p->TR_SIGMA_MIN; /* Besselink 2010 eq 19 */
    q = Vx / vxlow;
    q = q > 1.0 ? 1.0 : (q < -1.0 ? -1.0 : q);
    /* smooth sign of the rolling direction; sin(+-PI/2) is exactly +-1 in double */
    k->My_sign = q == 1.0 ? 1.0 : (q == -1.0 ? -1.0 : sin(0.5 * PI * q));
    return MF_OK;
}

/* Leak rates a_x, a_y [1/s] with the deflection limiter. */
static void leak(const MFParams *p, const MTKin *k, const double x[2], double *ax, double *ay)
{
    double gx = fabs(x[0]) / (k->sigx * p->TR_KAPPA_LIM) - 1.0, gy = fabs(x[1]) / (k->sigy * p->TR_TANALPHA_LIM) - 1.0;
    gx = gx > 0.0 ? gx : 0.0; /* deflection limiter */
    gy = gy > 0.0 ? gy : 0.0;
    *ax = (fabs(k->Vx) + p->TR_LIM_GAIN * fabs(k->Vsx) * gx * gx) / k->sigx;
    *ay = (fabs(k->Vx) + p->TR_LIM_GAIN * fabs(k->Vsy) * gy * gy) / k->sigy;
}

void mt_rates(const MFParams *p, const MTKin *k, const double x[2], double dx[2])
{
    double ax, ay;
    leak(p, k, x, &ax, &ay);
    dx[0] = -k->Vsx - ax * x[0]; /* Pacejka 2012 §7.2.1: du/dt + |Vx|/sigma_kappa*u = -Vsx */
    dx[1] = k->Vsy - ay * x[1];  /* Pacejka 2012 §7.2.1: dv/dt + |Vx|/sigma_alpha*v = Vsy (ISO sign) */
}

int mt_outputs(const MFParams *p, int use_mode, const MTKin *k, const double x[2], unsigned want,
               MTOutputs *out, mf_warning_fn warn, void *ctx)
{
    double dx[2];
    MFInputs ev = k->ev;
    int rc;
    mt_rates(p, k, x, dx);
    out->kappa_t = (x[0] + k->w * p->TR_TAU_X * dx[0]) / k->sigx;    /* low-speed damping (§7.3) */
    out->alpha_t = atan((x[1] + k->w * p->TR_TAU_Y * dx[1]) / k->sigy); /* tan alpha' = v/sigma_alpha */
    ev.kappa = out->kappa_t;
    ev.alpha = out->alpha_t;
    rc = mf_evaluate_want(p, use_mode, &ev, want, &out->ss, warn, ctx);
    if (rc != MF_OK) return rc;
    /* rolling offsets fade out below VXLOW (an output is valid only when its group is wanted) */
    if (want & MF_WANT_FX) out->ss.Fx -= k->w * k->zero.Fx;
    if (want & MF_WANT_FY) out->ss.Fy -= k->w * k->zero.Fy;
    if (want & MF_WANT_MZ) out->ss.Mz -= k->w * k->zero.Mz;
    if (want & MF_WANT_MY) out->ss.My *= k->My_sign; /* rolling resistance opposes the rolling direction */
    return MF_OK;
}

void mt_step(const MFParams *p, const MTKin *k, double x[2], double h)
{
    double ax, ay, ah, phi;
    leak(p, k, x, &ax, &ay);
    ah = ax * h;
    phi = ah < 1e-12 ? h : -expm1(-ah) / ax;
    x[0] = x[0] * exp(-ah) - k->Vsx * phi; /* exact solution of du/dt = -Vsx - a_x*u over h */
    ah = ay * h;
    phi = ah < 1e-12 ? h : -expm1(-ah) / ay;
    x[1] = x[1] * exp(-ah) + k->Vsy * phi;
}

/* Is the deflection limiter inactive over a step of length H (state s, forcing f, leak |Vx|/sig)?  The
 * linear lag moves s monotonically towards f/a (a > 0) or drifts linearly (a = 0), so it suffices that
 * the start and the end point (or the steady state) lie within the limit. */
static int limiter_idle(double s, double f, double sig, double lim, double absVx, double H)
{
    double ulim = sig * lim, a = absVx / sig, end;
    if (fabs(s) > ulim) return 0;
    end = a > 0.0 ? f / a : s + f * H;
    return fabs(end) <= ulim;
}

void mt_advance(const MFParams *p, const MTKin *k, double x[2], double H)
{
    double h, absVx = fabs(k->Vx);
    long n, i;
    if (!(H > 0.0)) return;
    if (limiter_idle(x[0], -k->Vsx, k->sigx, p->TR_KAPPA_LIM, absVx, H) &&
        limiter_idle(x[1], k->Vsy, k->sigy, p->TR_TANALPHA_LIM, absVx, H)) {
        mt_step(p, k, x, H); /* exact solution of the linear lag: one step */
        return;
    }
    n = (long)ceil(H / p->TR_CS_STEP - 1e-9);
    if (n < 1) n = 1;
    h = H / (double)n;
    for (i = 0; i < n; i++) mt_step(p, k, x, h);
}
