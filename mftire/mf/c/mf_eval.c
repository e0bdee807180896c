/*
 * mf_eval.c -- Magic Formula 6.1 / 6.2 / 5.2 steady-state equations in C99.
 *
 * A line-by-line port of mftire's Python evaluator (mftire/mf/): the section
 * headers below name the Python module each block mirrors.  Equation numbers are
 * those of Pacejka (2012) unless a comment says otherwise.  The reference for
 * numerical agreement is MFeval 4.0; where it departs from the book to match
 * TNO's solver we follow it, and each such place is marked "MFeval departure:"
 * exactly as in the Python sources.
 *
 * Arithmetic is written in the same order as the Python expressions so that
 * both implementations round alike.
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "mf_eval.h"

/* Linkage of the model's functions: static here; the array kernel (mf_kernel.c) defines it as
 * always-inline so that its lane loops hold the whole model and can be vectorised. */
#ifndef MF_FN
#define MF_FN static
#endif

/* The model extensions: the code generated from mftire.mf.extensions (the term table, the variables and
 * forms: section extensions.py) and, through it, its interface to this file (mf_ext.h: Cond, the increments,
 * the table form). */
#include "mf_ext_gen.h"
#include "mf_ext.h"

/* Small number against singularities at zero speed (Pacejka 2012, eq 4.E6a). */
#define MF_EPSILON 1e-6
#define MF_PI 3.14159265358979323846

/* ------------------------------------------------------------------ helpers */

/* numpy.sign: -1, 0, +1, NaN for NaN */
MF_FN double sgn(double x)
{
    if (x > 0.0) return 1.0;
    if (x < 0.0) return -1.0;
    if (x == 0.0) return 0.0;
    return x; /* NaN */
}

/* sign(x) with sign(0) = +1, used against 0/0 (Pacejka 2012, p. 177). */
MF_FN double sign_nonzero(double x) { return sgn(x) + (x == 0.0 ? 1.0 : 0.0); }

MF_FN double sq(double x) { return x * x; }

/* cos(atan(x)) in its exact algebraic form 1/sqrt(1 + x^2) (one square root instead of two
 * transcendental calls; agrees with numpy's cos(arctan(x)) to rounding). */
MF_FN double cos_atan(double x) { return 1.0 / sqrt(1.0 + x * x); }

/* Normalised load increment dfz = (Fz - Fz0')/Fz0' with Fz0' = LFZO*FNOMIN (eqs 4.E1, 4.E2a) and pressure
 * increment dpi = (P - NOMPRES)/NOMPRES (eq 4.E2b): mftire.mf.basic.increments. */
MF_FN double mf_fz0p(const MFParams *p) { return p->LFZO * p->FNOMIN; /* eq 4.E1 */ }
MF_FN double mf_dfz(const MFParams *p, double Fz) { return (Fz - mf_fz0p(p)) / mf_fz0p(p); /* eq 4.E2a */ }
MF_FN double mf_dpi(const MFParams *p, double P) { return (P - p->NOMPRES) / p->NOMPRES; /* eq 4.E2b */ }

/* ------------------------------------------------------------------ family.py (PAC2002) */

/* Internal model code of a PAC2002 file (no FITTYP in the file): mftire.mf.spec.PAC2002_CODE. */
#define MF_PAC2002_CODE MF_SPEC_PAC2002_CODE

/* The MF 5.2 equation family: FITTYP 6 and PAC2002. */
MF_FN int is_mf52(const MFParams *p) { return p->FITTYP == 6.0 || p->FITTYP == MF_PAC2002_CODE; }

MF_FN int is_pac2002(const MFParams *p) { return p->FITTYP == MF_PAC2002_CODE; }

/* fmax as glibc computes it (x when x >= y or y is NaN, else y), written out so that the
 * array kernel can vectorise it: max(NaN, 0) = 0 as MATLAB's max() in the reference. */
MF_FN double max_num(double x, double y) { return (x >= y || isnan(y)) ? x : y; }

/* numpy.clip(v, lo, hi): NaN passes through */
MF_FN double clip(double v, double lo, double hi)
{
    if (v < lo) v = lo;
    if (v > hi) v = hi;
    return v;
}

/* Evaluation context: decoded mode, warning mask.  The equations only set bits of the mask
 * (no formatting, no calls with side effects: the array kernel vectorises them across points);
 * mf_warning_text gives the message of a kind afterwards. */
typedef struct {
    int limits, alpha_star, turn_slip, combined;
    /* The zero-camber Fy0 of the combined-slip aligning moment reuses the Fy0 already computed
     * where there is no camber: -1 decides per point (one point: the FMU), 0 / 1 for a whole
     * batch without / with camber somewhere (the array kernel; numpy decides per batch). */
    int batch_camber;
    /* 1: the loaded radius by the closed form whatever the file (the array kernel's vectorised
     * loops, which cannot hold the MF 6.2 root iteration; the kernel computes it again for MF 5.2
     * and 6.2 files); 0: by the file's model (loaded_radius). */
    int closed_radius;
    unsigned long warnings;
} Ctx;

MF_FN void flag(Ctx *x, int kind) { x->warnings |= 1UL << kind; }

/* The message of warning kind `kind` (the texts of mftire/mf/spec.py WARNINGS; for the limits: the file's
 * limit value; for the data variables: their names). */
void mf_warning_text(const MFParams *p, int kind, char *buf, unsigned long n)
{
    static const MFWarningSpec specs[MF_W_COUNT] = MF_WARNING_SPECS;
    const char *input;
    if (n == 0) return;
    buf[0] = '\0';
    if (kind < 0 || kind >= MF_W_COUNT) return;
    input = specs[kind].input;
#if MF_N_DATA > 0
    if (kind >= MF_W_NAN_DATA0 && kind < MF_W_NAN_DATA0 + MF_N_DATA) {
        static const char *const data_names[MF_N_DATA] = MF_DATA_NAMES;
        input = data_names[kind - MF_W_NAN_DATA0];
    }
#endif
    if (specs[kind].limit >= 0)
        snprintf(buf, n, specs[kind].format, ((const double *)p)[specs[kind].limit]);
    else if (input)
        snprintf(buf, n, specs[kind].format, input);
    else
        snprintf(buf, n, "%s", specs[kind].format);
}

/* ------------------------------------------------------------------ modes.py */

int mf_check_mode(int code, char *msg, unsigned long n)
{
    int hundreds = code / 100, tens = (code / 10) % 10, units = code % 10;
    if (code < 100 || code > 999) {
        snprintf(msg, n, "useMode must be a three-digit integer such as 111, got %d", code);
        return MF_BAD_MODE;
    }
    if (hundreds != 1 && hundreds != 2) {
        snprintf(msg, n, "useMode %d: hundreds digit must be 1 (limit checks) or 2 (none)", code);
        return MF_BAD_MODE;
    }
    if (tens != 1 && tens != 2) {
        snprintf(msg, n, "useMode %d: tens digit must be 1 (no alpha-star) or 2 (alpha-star)", code);
        return MF_BAD_MODE;
    }
    if (units > 2) {
        snprintf(msg, n, "useMode %d: units digit must be 0 (pure slip), 1 (combined) or 2 (combined + turn slip)",
                 code);
        return MF_BAD_MODE;
    }
    return MF_OK;
}

int mf_check_fittyp(const MFParams *p, char *msg, unsigned long n)
{
    static const double families[MF_SPEC_N_FAMILIES] = MF_SPEC_FAMILIES;
    int k;
    for (k = 0; k < MF_SPEC_N_FAMILIES; k++)
        if (p->FITTYP == families[k]) return MF_OK;
    snprintf(msg, n, "FITTYP %.17g is not evaluated: mftire evaluates the model codes of " MF_SPEC_FAMILY_NAMES,
             p->FITTYP);
    return MF_BAD_FITTYP;
}

/* ------------------------------------------------------------------ inputs.py */

/* Cond, one operating point as the equations see it: mf_ext.h (the model extensions read it too). */

/* The pressure clipped to [PRESMIN, PRESMAX] with a warning (limit mode). */
MF_FN double limit_pressure(const MFParams *p, Ctx *m, double P)
{
    if (P < p->PRESMIN) flag(m, MF_W_P_LOW);
    if (P > p->PRESMAX) flag(m, MF_W_P_HIGH);
    return P < p->PRESMIN ? p->PRESMIN : (P > p->PRESMAX ? p->PRESMAX : P);
}

/* The inclination angle clipped to [CAMMIN, CAMMAX] (limit mode; the warnings are condition_inputs'). */
MF_FN double limit_camber(const MFParams *p, double gamma)
{
    return gamma < p->CAMMIN ? p->CAMMIN : (gamma > p->CAMMAX ? p->CAMMAX : gamma);
}

MF_FN void condition_inputs(const MFParams *p, Ctx *m, double Fz, double kappa, double alpha, double gamma,
                             double phit, double Vx, double P, Cond *c)
{
    double uFz, ukappa, ualpha, ugamma, uVx, ukappa_low, Fz_low, smooth = 1.0;
    int low_speed = 0;
    if (Fz < 0.0) Fz = 0.0; /* negative loads mean lift-off */
    uFz = Fz; ukappa = kappa; ualpha = alpha; ugamma = gamma; uVx = Vx;
    ukappa_low = kappa;
    Fz_low = Fz;

    if (m->limits) {
        double VXLOW = p->VXLOW, speed_sum;
        /* MFeval departure: turn slip is scaled by cos(alpha) ("empirically discovered"
         * to match TNO). */
        phit = phit * cos(alpha);
        low_speed = fabs(Vx) <= VXLOW;
        if (low_speed) {
            /* Smooth (cosine) and linear reduction factors below VXLOW; 1 elsewhere. */
            double linear;
            smooth = 1.0 - 0.5 * (1.0 + cos(MF_PI * Vx / VXLOW));
            linear = fabs(Vx / VXLOW);
            ukappa_low = kappa * linear;
            phit = phit * linear;
            kappa = kappa * linear;
        }
        if (Vx < 0.0) phit = -phit;
        /* Slip angle is also reduced when |Vx| + |Vsy| < VXLOW. */
        speed_sum = fabs(Vx) + fabs(tan(alpha) * Vx);
        if (speed_sum < VXLOW) alpha = alpha * (speed_sum / VXLOW);

        if (alpha < p->ALPMIN) flag(m, MF_W_ALPHA_LOW);
        if (alpha > p->ALPMAX) flag(m, MF_W_ALPHA_HIGH);
        alpha = alpha < p->ALPMIN ? p->ALPMIN : (alpha > p->ALPMAX ? p->ALPMAX : alpha);
        if (gamma < p->CAMMIN) flag(m, MF_W_GAMMA_LOW);
        if (gamma > p->CAMMAX) flag(m, MF_W_GAMMA_HIGH);
        gamma = limit_camber(p, gamma);

        if (Fz > p->FZMAX) {
            flag(m, MF_W_FZ_HIGH);
            Fz = p->FZMAX;
        }
        if (Fz < p->FZMIN) flag(m, MF_W_FZ_LOW);
        Fz_low = Fz < p->FZMIN ? p->FZMIN : Fz;
        P = limit_pressure(p, m, P);
        if (kappa < p->KPUMIN) flag(m, MF_W_KAPPA_LOW);
        if (kappa > p->KPUMAX) flag(m, MF_W_KAPPA_HIGH);
        kappa = kappa < p->KPUMIN ? p->KPUMIN : (kappa > p->KPUMAX ? p->KPUMAX : kappa);
        if (low_speed) flag(m, MF_W_LOW_SPEED);
    }

    /* MFeval departure: the reported slip angle is zero at exactly zero speed. */
    if (uVx == 0.0) ualpha = 0.0;
    c->Fz = Fz; c->Fz_low = Fz_low; c->kappa = kappa; c->alpha = alpha; c->gamma = gamma;
    c->phit = phit; c->P = P; c->Vx = uVx; c->uFz = uFz; c->ukappa = ukappa; c->ukappa_low = ukappa_low;
    c->ualpha = ualpha; c->ugamma = ugamma; c->low_speed = low_speed; c->smooth = smooth;
    c->omega = 0.0; c->phi = 0.0; c->eps_gamma = 0.0;
}

/*
 * Spin slip phi and camber reduction factor epsilon_gamma.
 * phi = (psi_dot - (1 - eps_gamma)*omega*sin(gamma)) / Vc'  (eq 4.76, with psi_dot =
 * -phit*Vc' from eq 4.75); eps_gamma = PECP1*(1 + PECP2*dfz) (eq 4.90).
 * MFeval departure: Vc' is the contact-centre speed sqrt(Vx^2 + Vsy^2) (TNO equation
 * manual) protected to +-VXLOW below VXLOW, and eq 4.76 is used without the book's
 * sign change because the road z axis points up.
 */
MF_FN void turn_slip_spin(const MFParams *p, Cond *c)
{
    double dfz = mf_dfz(p, c->Fz); /* eq 4.E2a */
    double Vsy = -tan(c->alpha) * fabs(c->Vx);
    double V = sqrt(sq(c->Vx) + sq(Vsy));
    double eps_gamma = p->PECP1 * (1.0 + p->PECP2 * dfz); /* eq 4.90 */
    int low = fabs(c->Vx) < p->VXLOW;
    double s = sgn(c->Vx), Vc_prime, psi_dot;
    if (s == 0.0) s = 1.0;
    Vc_prime = low ? p->VXLOW * s : V;
    psi_dot = -c->phit * Vc_prime; /* eq 4.75 */
    c->phi = (1.0 / Vc_prime) * (psi_dot - (1.0 - eps_gamma) * c->omega * sin(c->gamma)); /* eq 4.76 */
    c->eps_gamma = eps_gamma;
}

/* ------------------------------------------------------------------ basic.py */

typedef struct {
    double Fz0p;        /* adapted nominal load Fz0' = LFZO*FNOMIN [N] (eq 4.E1) */
    double dfz;         /* eq 4.E2a */
    double dpi;         /* eq 4.E2b */
    double alpha_star;  /* eq 4.E3 */
    double gamma_star;  /* eq 4.E4 */
    double alpha_prime; /* eq 4.E6 */
    double LMUX_star, LMUY_star, LMUX_prime, LMUY_prime; /* eqs 4.E7, 4.E8 */
} Basic;

MF_FN void basic(const MFParams *p, const Ctx *m, const Cond *c, double muRoad, Basic *b)
{
    double absVx, Vsy, Vc, Vc_prime, s, LMUV, Amu;
    b->Fz0p = mf_fz0p(p);          /* eq 4.E1 */
    b->dfz = mf_dfz(p, c->Fz);     /* eq 4.E2a */
    b->dpi = mf_dpi(p, c->P);      /* eq 4.E2b */
    absVx = fabs(c->Vx);
    /* Vsx = -kappa*|Vx| (eq 4.E5) and Vs (eq 3.39) only matter when LMUV != 0 */
    /* ISO sign convention: no minus sign in eq 2.12 (the book is in adapted SAE). */
    Vsy = tan(c->alpha) * absVx;                  /* eq 2.12 / 4.E3 */
    Vc = sqrt(sq(c->Vx) + sq(Vsy));               /* contact-centre speed, Vcy = Vsy */
    if (m->alpha_star) {
        b->alpha_star = tan(c->alpha) * sgn(c->Vx); /* eq 4.E3 */
        b->gamma_star = sin(c->gamma);              /* eq 4.E4 */
    } else {
        b->alpha_star = c->alpha;
        b->gamma_star = c->gamma;
    }
    s = (Vc == 0.0) ? 1.0 : sgn(Vc);
    Vc_prime = Vc + MF_EPSILON * s;               /* eq 4.E6a */
    b->alpha_prime = acos(c->Vx / Vc_prime);      /* eq 4.E6 */
    /* Friction decaying with slip speed: LMUV is not part of MF 6.1/6.2 .tir files,
     * so it is 0 as in the reference evaluator; Amu = 1 (MFeval departure: the book
     * suggests Amu = 10, Amu = 1 matches TNO).  muRoad scales LMUX and LMUY; the model
     * extensions act through the scaling factors of p (apply_extensions). */
    LMUV = 0.0;
    (void)LMUV;
    b->LMUX_star = p->LMUX * muRoad;              /* eq 4.E7 with LMUV = 0 */
    b->LMUY_star = p->LMUY * muRoad;              /* eq 4.E7 with LMUV = 0 */
    Amu = 1.0;
    b->LMUX_prime = Amu * b->LMUX_star / (1.0 + (Amu - 1.0) * b->LMUX_star); /* eq 4.E8 */
    b->LMUY_prime = Amu * b->LMUY_star / (1.0 + (Amu - 1.0) * b->LMUY_star); /* eq 4.E8 */
    if (is_pac2002(p) && p->LMUV != 0.0) {
        /* PAC2002: friction decays with the slip speed, lambda_mu/(1 + LMUV*Vs/V0) (Pacejka 2006
           eq 4.E7; Vsx = -kappa*|Vx| eq 4.E5, Vs eq 3.39); Amu = 1, so lambda' = lambda* (eq 4.E8) */
        double f = 1.0 + p->LMUV * sqrt(sq(c->kappa * absVx) + sq(Vsy)) / p->LONGVL;
        b->LMUX_star /= f;
        b->LMUY_star /= f;
        b->LMUX_prime = b->LMUX_star;
        b->LMUY_prime = b->LMUY_star;
    }
}

/* ------------------------------------------------------------------ vertical.py (radii) */

/* Free-spinning radius R_omega with centrifugal growth [m] (Besselink 2010 eq 1). */
MF_FN double free_radius(const MFParams *p, double omega)
{
    double R0 = p->UNLOADED_RADIUS;
    return R0 * (p->Q_RE0 + p->Q_V1 * sq((omega * R0) / p->LONGVL));
}

/* Effective rolling radius Re = Romega - re_deflection [m] (Besselink 2010 eq 7); the
 * deflection term does not depend on omega, so the iteration below computes it once. */
MF_FN double re_deflection(const MFParams *p, double Fz, double Cz)
{
    double Fz0 = p->FNOMIN;
    return (Fz0 / Cz) * (p->DREFF * atan(p->BREFF * (Fz / Fz0)) + p->FREFF * (Fz / Fz0));
}

/* The fixed-point iteration for Re when omega is not given (below): start and tolerance of
 * the reference evaluator. */
#define MF_RE_START 0.965 /* Re starts at 0.965*R0 */
#define MF_RE_TOL 1e-9    /* [m] */

/* The load part of Re, Romega - Re [m]: Besselink 2010 eq 7 with Cz of eq 5. */
MF_FN double re_load_deflection(const MFParams *p, double Fz, double dpi)
{
    double Cz = p->VERTICAL_STIFFNESS * (1.0 + p->PFZ1 * dpi); /* Besselink 2010 eq 5 */
    return re_deflection(p, Fz, Cz);
}

/* Is the iteration still moving (the reference's loop condition)?  NaN stops it. */
MF_FN int re_moving(double Re, double Re_old) { return fabs(Re_old - Re) > MF_RE_TOL; }

/* One update: omega = (1 + kappa)*Vx/Re (eq 2.5), Romega (Besselink 2010 eq 1), Re (eq 7). */
MF_FN void re_update(const MFParams *p, double defl, double kappa, double Vx, double *Re, double *Re_old,
                      double *omega, double *Romega)
{
    *Re_old = *Re;
    *omega = (kappa * Vx + Vx) / *Re; /* eq 2.5 */
    *Romega = free_radius(p, *omega);
    *Re = *Romega - defl;
}

/* Re, Romega and omega for a given wheel spin omega_in (no iteration). */
MF_FN void re_given_omega(const MFParams *p, double defl, double omega_in, double *Re, double *Romega,
                           double *omega)
{
    *omega = omega_in + DBL_EPSILON; /* as the reference: avoids Romega = 0 exactly */
    *Romega = free_radius(p, *omega);
    *Re = *Romega - defl;
}

/*
 * Effective rolling radius, free radius and wheel spin.  When omega is not given it
 * is estimated from omega = (1 + kappa)*Vx/Re (eq 2.5) by fixed-point iteration on
 * Re, started at 0.965*R0 as the reference evaluator does.
 * MFeval departure: the reference stops a batch as soon as one point has converged;
 * for a single point that is ordinary convergence to |dRe| <= 1e-9 m.  At most *kmax
 * updates are made and *kmax returns how many were (the array kernel, mf_kernel.c, finds
 * the batch's count with a first pass and then makes exactly that many for every point).
 */
MF_FN void effective_rolling_radius(const MFParams *p, const Cond *c, double dpi, int omega_given,
                                     double omega_in, int *kmax, double *Re_out, double *Romega_out,
                                     double *omega_out)
{
    double defl = re_load_deflection(p, c->uFz, dpi), Re, Re_old, omega, Romega;
    int i;
    if (omega_given) {
        re_given_omega(p, defl, omega_in, Re_out, Romega_out, omega_out);
        return;
    }
    Re = p->UNLOADED_RADIUS * MF_RE_START;
    Re_old = p->UNLOADED_RADIUS;
    omega = 0.0;
    Romega = p->UNLOADED_RADIUS;
    for (i = 0; i < *kmax; i++) {
        if (!re_moving(Re, Re_old)) break;
        re_update(p, defl, c->ukappa, c->Vx, &Re, &Re_old, &omega, &Romega);
    }
    *kmax = i; /* the number of updates made */
    *Re_out = Re;
    *Romega_out = Romega;
    *omega_out = omega;
}

/* ------------------------------------------------------------------ turnslip.py */

/* Fx peak reduction zeta1 (eqs 4.105, 4.106). */
MF_FN double zeta1(const MFParams *p, double dfz, double kappa, double phi)
{
    double Bxp = p->PDXP1 * (1.0 + p->PDXP2 * dfz) * cos_atan(p->PDXP3 * kappa); /* eq 4.106 */
    return cos_atan(Bxp * p->UNLOADED_RADIUS * phi);                           /* eq 4.105 */
}

/* Fy peak reduction zeta2 and cornering-stiffness reduction zeta3 (eqs 4.77-4.79). */
MF_FN void zeta2_zeta3(const MFParams *p, double dfz, double alpha, double phi, double *z2, double *z3)
{
    double R0 = p->UNLOADED_RADIUS, Byp, aphi;
    *z3 = cos_atan(p->PKYP1 * sq(R0) * sq(phi));                                     /* eq 4.79 */
    Byp = p->PDYP1 * (1.0 + p->PDYP2 * dfz) * cos_atan(p->PDYP3 * tan(alpha));        /* eq 4.78 */
    aphi = fabs(phi);
    *z2 = cos_atan(Byp * (R0 * aphi + p->PDYP4 * sqrt(R0 * aphi)));                  /* eq 4.77 */
}

/* Pneumatic-trail reduction zeta5 (eq 4.91). */
MF_FN double zeta5(const MFParams *p, double phi) { return cos_atan(p->QDTP1 * p->UNLOADED_RADIUS * phi); }

/* Residual-torque slope reduction zeta6 (eq 4.102). */
MF_FN double zeta6(const MFParams *p, double phi) { return cos_atan(p->QBRP1 * p->UNLOADED_RADIUS * phi); }

/* ------------------------------------------------------------------ longitudinal.py */

/* MF_W_OF_FX, MF_W_OF_FY, MF_W_OF_MZ (mf_spec_gen.h): the warnings of the curvature clips below, by the
 * channel group that raises them. */

/* Curvature factors must not exceed 1; clipped with a warning in limit mode. */
MF_FN double clip_curvature(Ctx *m, double E, int kind)
{
    if (m->limits && E > 1.0) {
        flag(m, kind);
        return 1.0;
    }
    return E;
}

/* Longitudinal slip stiffness Kxk [N] (eq 4.E15). */
MF_FN double kxk(const MFParams *p, double Fz, double dfz, double dpi)
{
    return Fz * (p->PKX1 + p->PKX2 * dfz) * exp(p->PKX3 * dfz) * (1.0 + p->PPX1 * dpi + p->PPX2 * sq(dpi)) *
           p->LKX; /* eq 4.E15 */
}

/* Longitudinal friction coefficient mu_x (eq 4.E13; 0 at Fz = 0). */
MF_FN double mu_x(const MFParams *p, const Cond *c, const Basic *b)
{
    double dfz = b->dfz, dpi = b->dpi;
    if (c->Fz == 0.0) return 0.0;
    return (p->PDX1 + p->PDX2 * dfz) * (1.0 + p->PPX3 * dpi + p->PPX4 * sq(dpi)) * (1.0 - p->PDX3 * sq(c->gamma)) *
           b->LMUX_star; /* eq 4.E13 */
}

/* Lateral friction coefficient mu_y at the camber gamma_star (eq 4.E23). */
MF_FN double mu_y(const MFParams *p, const Basic *b, double gamma_star)
{
    double dfz = b->dfz, dpi = b->dpi;
    return (p->PDY1 + p->PDY2 * dfz) * (1.0 + p->PPY3 * dpi + p->PPY4 * sq(dpi)) * (1.0 - p->PDY3 * sq(gamma_star)) *
           b->LMUY_star; /* eq 4.E23 */
}

/* Pure longitudinal force: Fx0 [N], mux [-], Kxk [N]. */
MF_FN void fx0(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, double z1, double *Fx0_out,
                double *mux_out, double *Kxk_out)
{
    double Fz = c->Fz, dfz = b->dfz, dpi = b->dpi;
    double Cx, mux, Dx, Kxk, Bx, SHx, SVx, kappax, Ex, Bk, Fx0;
    Cx = p->PCX1 * p->LCX; /* eq 4.E11 */
    mux = mu_x(p, c, b); /* eq 4.E13 */
    Dx = mux * Fz * z1; /* eq 4.E12 */
    Kxk = kxk(p, Fz, dfz, dpi); /* eq 4.E15 */
    Bx = Kxk / (Cx * Dx + MF_EPSILON * sign_nonzero(Dx)); /* eq 4.E16 */
    SHx = (p->PHX1 + p->PHX2 * dfz) * p->LHX * c->smooth; /* eq 4.E17 (low-speed reduced) */
    SVx = Fz * (p->PVX1 + p->PVX2 * dfz) * p->LVX * b->LMUX_prime * z1 * c->smooth; /* eq 4.E18 */
    kappax = c->kappa + SHx; /* eq 4.E10 */
    Ex = (p->PEX1 + p->PEX2 * dfz + p->PEX3 * sq(dfz)) * (1.0 - p->PEX4 * sgn(kappax)) * p->LEX;
    Ex = clip_curvature(m, Ex, MF_W_EX); /* eq 4.E14 */
    Bk = Bx * kappax;
    Fx0 = Dx * sin(Cx * atan(Bk - Ex * (Bk - atan(Bk)))) + SVx; /* eq 4.E9 */
    if (c->Vx < 0.0) Fx0 = -Fx0; /* driving backwards */
    *Fx0_out = Fx0;
    *mux_out = mux;
    *Kxk_out = Kxk;
}

/* Combined-slip longitudinal force Fx = Gxa*Fx0 [N] (eqs 4.E50-4.E57). */
MF_FN double fx_combined(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, double Fx0)
{
    double Cxa = p->RCX1; /* eq 4.E55 */
    double Exa = clip_curvature(m, p->REX1 + p->REX2 * b->dfz, MF_W_EXA); /* eq 4.E56 */
    double SHxa = p->RHX1; /* eq 4.E57 */
    double Bxa = (p->RBX1 + p->RBX3 * sq(b->gamma_star)) * cos_atan(p->RBX2 * c->kappa) * p->LXAL; /* 4.E54 */
    double alphas = b->alpha_star + SHxa; /* eq 4.E53 */
    double Bs = Bxa * SHxa;
    double Gxa0 = cos(Cxa * atan(Bs - Exa * (Bs - atan(Bs)))); /* eq 4.E52 */
    double Ba = Bxa * alphas;
    double Gxa = cos(Cxa * atan(Ba - Exa * (Ba - atan(Ba)))) / Gxa0; /* eq 4.E51 */
    return Gxa * Fx0; /* eq 4.E50 */
}

/* ------------------------------------------------------------------ lateral.py */

typedef struct {
    double Fy0, muy, Kya, Kyg0, SHy, SVy, By, Cy, zeta2;
} PureLat;

/* Cornering stiffness Kya [N/rad] (eq 4.E25). */
MF_FN double kya(const MFParams *p, double Fz, double Fz0p, double dpi, double gamma_star, double zeta3)
{
    return p->PKY1 * Fz0p * (1.0 + p->PPY1 * dpi) * (1.0 - p->PKY3 * fabs(gamma_star)) *
           sin(p->PKY4 * atan((Fz / Fz0p) / ((p->PKY2 + p->PKY5 * sq(gamma_star)) * (1.0 + p->PPY2 * dpi)))) *
           zeta3 * p->LKY;
}

/* Pure lateral force at inclination gamma_star (eqs 4.E19-4.E30). */
MF_FN void fy0(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, double gamma_star, int turn_slip,
                int ey_kind, PureLat *lat)
{
    double Fz = c->Fz, dfz = b->dfz, dpi = b->dpi, Fz0p = b->Fz0p;
    double zeta2 = 1.0, zeta3 = 1.0, zeta0, zeta4, Kya, SVyg, Kyg0, sKya, SHy, SVy, alphay, Cy, muy, Dy, Ey, By, Ba,
           Fy0;
    int mf52 = is_mf52(p);
    if (turn_slip) zeta2_zeta3(p, dfz, c->alpha, c->phi, &zeta2, &zeta3);

    Kya = kya(p, Fz, Fz0p, dpi, gamma_star, zeta3); /* eq 4.E25 */
    SVyg = Fz * (p->PVY3 + p->PVY4 * dfz) * gamma_star * p->LKYC * b->LMUY_prime * zeta2; /* eq 4.E28 */
    if (mf52) {
        /* MF 5.2 (TNO MF-Tyre equation manual), as the reference evaluator does. */
        double Kya0_52 = p->PKY1 * Fz0p * sin(p->PKY4 * atan(Fz / (p->PKY2 * Fz0p))) * p->LKYC;
        Kyg0 = (p->PHY3 * Kya0_52 + Fz * (p->PVY3 + p->PVY4 * dfz)) * p->LKYC;
    } else {
        Kyg0 = Fz * (p->PKY6 + p->PKY7 * dfz) * (1.0 + p->PPY5 * dpi) * p->LKYC; /* eq 4.E30 */
    }

    sKya = sign_nonzero(Kya);
    if (turn_slip) {
        /* Lateral shift due to spin (eqs 4.80-4.89). */
        double R0 = p->UNLOADED_RADIUS, Kya0, Kya_prime, Kya0_prime, CHyp, DHyp, EHyp, KyRp0, BHyp, x, SHyp;
        /* MFeval departure (after IPG CarMaker): Kya0 is Kya at zero camber. */
        Kya0 = kya(p, Fz, Fz0p, dpi, 0.0, zeta3);
        Kya_prime = Kya + MF_EPSILON * sKya; /* eq 4.E39 */
        Kya0_prime = Kya0 + MF_EPSILON * sign_nonzero(Kya0);
        CHyp = p->PHYP1; /* eq 4.85 */
        DHyp = (p->PHYP2 + p->PHYP3 * dfz) * sgn(c->Vx); /* eq 4.86 */
        EHyp = p->PHYP4; /* eq 4.87 */
        if (m->limits && EHyp > 1.0) EHyp = 1.0;
        KyRp0 = Kyg0 / (1.0 - c->eps_gamma); /* eq 4.89 */
        BHyp = KyRp0 / (CHyp * DHyp * Kya0_prime); /* eq 4.88 */
        x = BHyp * R0 * c->phi;
        /* eq 4.80; at standstill DHyp = 0 and BHyp is infinite: SHyp takes its limit 0 */
        SHyp = DHyp == 0.0 ? 0.0 : DHyp * sin(CHyp * atan(x - EHyp * (x - atan(x)))) * sgn(c->Vx);
        zeta0 = 0.0; /* eq 4.83 */
        zeta4 = 1.0 + SHyp - SVyg / Kya_prime; /* eq 4.84 */
    } else {
        zeta0 = 1.0;
        zeta4 = 1.0;
    }

    if (mf52) {
        SHy = (p->PHY1 + p->PHY2 * dfz) * p->LHY + p->PHY3 * gamma_star * p->LKYC; /* MF 5.2 manual */
    } else {
        SHy = (p->PHY1 + p->PHY2 * dfz) * p->LHY + ((Kyg0 * gamma_star - SVyg) / (Kya + MF_EPSILON * sKya)) * zeta0 +
              zeta4 - 1.0; /* eq 4.E27 */
    }
    SVy = Fz * (p->PVY1 + p->PVY2 * dfz) * p->LVY * b->LMUY_prime * zeta2 + SVyg; /* eq 4.E29 */
    SVy = SVy * c->smooth;
    SHy = SHy * c->smooth;

    alphay = b->alpha_star + SHy; /* eq 4.E20 */
    Cy = p->PCY1 * p->LCY; /* eq 4.E21 */
    muy = mu_y(p, b, gamma_star); /* eq 4.E23 */
    Dy = muy * Fz * zeta2; /* eq 4.E22 */
    Ey = (p->PEY1 + p->PEY2 * dfz) *
         (1.0 + p->PEY5 * sq(gamma_star) - (p->PEY3 + p->PEY4 * gamma_star) * sign_nonzero(alphay)) * p->LEY;
    Ey = clip_curvature(m, Ey, ey_kind); /* eq 4.E24 */
    By = Kya / (Cy * Dy + MF_EPSILON * sign_nonzero(Dy)); /* eq 4.E26 */
    Ba = By * alphay;
    Fy0 = Dy * sin(Cy * atan(Ba - Ey * (Ba - atan(Ba)))) + SVy; /* eq 4.E19 */
    if (m->alpha_star && c->Vx < 0.0) Fy0 = -Fy0; /* driving backwards */
    if (Fz == 0.0) muy = 0.0;
    lat->Fy0 = Fy0; lat->muy = muy; lat->Kya = Kya; lat->Kyg0 = Kyg0; lat->SHy = SHy; lat->SVy = SVy;
    lat->By = By; lat->Cy = Cy; lat->zeta2 = zeta2;
}

/* Combined-slip lateral force (eqs 4.E58-4.E67): returns Fy, sets Gyk. */
MF_FN double fy_combined(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, double Fy0, double muy,
                          double zeta2, double *Gyk_out)
{
    double dfz = b->dfz, alpha_star = b->alpha_star, gamma_star = b->gamma_star;
    double DVyk, SVyk, SHyk, Eyk, Cyk, Byk, kappas, Bs, Gyk0, Bk, Gyk;
    DVyk = muy * c->Fz * (p->RVY1 + p->RVY2 * dfz + p->RVY3 * gamma_star) * cos_atan(p->RVY4 * alpha_star) *
           zeta2; /* eq 4.E67 */
    SVyk = DVyk * sin(p->RVY5 * atan(p->RVY6 * c->kappa)) * p->LVYKA; /* eq 4.E66 */
    SHyk = p->RHY1 + p->RHY2 * dfz; /* eq 4.E65 */
    Eyk = clip_curvature(m, p->REY1 + p->REY2 * dfz, MF_W_EYK); /* eq 4.E64 */
    Cyk = p->RCY1; /* eq 4.E63 */
    Byk = (p->RBY1 + p->RBY4 * sq(gamma_star)) * cos_atan(p->RBY2 * (alpha_star - p->RBY3)) * p->LYKA; /* 4.E62 */
    kappas = c->kappa + SHyk; /* eq 4.E61 */
    Bs = Byk * SHyk;
    Gyk0 = cos(Cyk * atan(Bs - Eyk * (Bs - atan(Bs)))); /* eq 4.E60 */
    Bk = Byk * kappas;
    Gyk = cos(Cyk * atan(Bk - Eyk * (Bk - atan(Bk)))) / Gyk0; /* eq 4.E59 */
    SVyk = SVyk * c->smooth;
    *Gyk_out = Gyk;
    return Gyk * Fy0 + SVyk; /* eq 4.E58 */
}

/* ------------------------------------------------------------------ aligning.py */

/* acos(x + 0i) of a real x as the C99 complex acos gives it, as (re, im), with real arithmetic only (MSVC has no
 * C99 complex): (acos x, -0) for |x| <= 1, (0, -acosh x) above 1, (pi, -acosh(-x)) below -1, NaN for NaN. */
MF_FN void acos_real(double x, double *re, double *im)
{
    if (isnan(x)) {
        *re = *im = x;
    } else if (x > 1.0) {
        *re = 0.0;
        *im = -acosh(x);
    } else if (x < -1.0) {
        *re = MF_PI;
        *im = -acosh(-x);
    } else {
        *re = acos(x);
        *im = -0.0;
    }
}

typedef struct {
    double alphar, alphat, Dr;
    double Cr, Cr_im; /* eq 4.E46, real and imaginary parts (complex in rare turn-slip cases, as in the reference) */
    double Br, Dt, Ct, Bt, Et, Kya_prime;
} AlignTerms;

/* Pneumatic trail t(alpha) (eq 4.E33/4.E73). */
MF_FN double trail_mf(double Dt, double Ct, double Bt, double Et, double alpha, double alpha_prime)
{
    double Ba = Bt * alpha;
    return Dt * cos(Ct * atan(Ba - Et * (Ba - atan(Ba)))) * cos(alpha_prime); /* eq 4.E33/4.E73 */
}

/* Trail and residual-torque factors (eqs 4.E33-4.E47; Besselink 2010 A58, A60). */
MF_FN void aligning_terms(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, const PureLat *lat, double Gyk,
                           AlignTerms *a)
{
    double R0 = p->UNLOADED_RADIUS;
    double dfz = b->dfz, dpi = b->dpi, gamma = c->gamma, gamma_star = b->gamma_star, alpha_star = b->alpha_star;
    double Fz, SHt, Kya_prime, SHf, alphar, alphat, z5 = 1.0, z6 = 1.0, Dt, Bt, Ct, Et, zeta0, zeta2, zeta8, Dr, Br;
    double zeta7, zeta7_im = 0.0; /* real and imaginary parts (no C99 complex: portable to MSVC) */
    if (m->limits)
        Fz = (c->Fz <= 0.0) ? 0.0 : c->Fz_low;
    else
        Fz = c->Fz;

    SHt = p->QHZ1 + p->QHZ2 * dfz + (p->QHZ3 + p->QHZ4 * dfz) * gamma_star; /* eq 4.E35 */
    Kya_prime = lat->Kya + MF_EPSILON * sign_nonzero(lat->Kya); /* eq 4.E39 */
    SHf = lat->SHy + lat->SVy / Kya_prime; /* eq 4.E38 */
    alphar = alpha_star + SHf; /* eq 4.E37 */
    alphat = alpha_star + SHt; /* eq 4.E34 */

    if (m->turn_slip) {
        z5 = zeta5(p, c->phi);
        z6 = zeta6(p, c->phi);
    }

    /* MFeval departure: Besselink 2010 eq A60 instead of book eqs 4.E42/4.E43 (QDZ3
     * multiplies gamma, not |gamma*|), which matches TNO for negative camber. */
    Dt = (p->QDZ1 + p->QDZ2 * dfz) * (1.0 - p->PPZ1 * dpi) * (1.0 + p->QDZ3 * gamma + p->QDZ4 * sq(gamma)) * Fz *
         (R0 / b->Fz0p) * p->LTR * z5; /* A60 */
    /* MFeval departure: Besselink 2010 eq A58 instead of book eq 4.E40 (no QBZ6). */
    Bt = (p->QBZ1 + p->QBZ2 * dfz + p->QBZ3 * sq(dfz)) * (1.0 + p->QBZ4 * gamma + p->QBZ5 * fabs(gamma)) * p->LKY /
         b->LMUY_star; /* A58 */
    Ct = p->QCZ1; /* eq 4.E41 */
    Et = (p->QEZ1 + p->QEZ2 * dfz + p->QEZ3 * sq(dfz)) *
         (1.0 + (p->QEZ4 + p->QEZ5 * gamma_star) * (2.0 / MF_PI) * atan(Bt * Ct * alphat));
    Et = clip_curvature(m, Et, MF_W_ET); /* eq 4.E44 */

    if (m->turn_slip) {
        double Fz0p = b->Fz0p, Mzp_inf, CDrp, DDrp, Kzgr0, BDrp, Drp, Mzp90;
        zeta0 = 0.0;
        zeta2 = lat->zeta2;
        /* Spin moment at 90 deg slip and its peak (eqs 4.94-4.103, TNO manual). */
        Mzp_inf = p->QCRP1 * fabs(lat->muy) * R0 * Fz * sqrt(Fz / Fz0p) * p->LMP; /* eq 4.95 */
        if (Mzp_inf < 0.0) Mzp_inf = 1e-6;
        CDrp = p->QDRP1; /* eq 4.96 */
        DDrp = Mzp_inf / sin(0.5 * MF_PI * CDrp); /* eq 4.94 */
        /* MFeval departure: QDZ8*QDZ9*dfz (product) as written in the reference evaluator. */
        Kzgr0 = Fz * R0 * (p->QDZ8 * p->QDZ9 * dfz + (p->QDZ10 + p->QDZ11 * dfz * fabs(gamma))) * p->LKZC;
        BDrp = Kzgr0 / (CDrp * DDrp * (1.0 - c->eps_gamma)); /* TNO manual */
        Drp = DDrp * sin(CDrp * atan(BDrp * R0 * c->phit)); /* TNO manual (uses phit) */
        Mzp90 = Mzp_inf * (2.0 / MF_PI) * atan(p->QCRP2 * R0 * fabs(c->phit)) * Gyk; /* eq 4.103 */
        /* acos of a ratio above one is complex in the reference; keep its real outcome. */
        /* MFeval departure (as aligning.py): Drp = 0 gives ratio 1, zeta7 = 0, Mzr = Dr. */
        acos_real(Drp == 0.0 ? 1.0 : Mzp90 / fabs(Drp), &zeta7, &zeta7_im); /* TNO manual */
        zeta7 *= 2.0 / MF_PI;
        zeta7_im *= 2.0 / MF_PI;
        zeta8 = 1.0 + Drp;
    } else {
        zeta0 = 1.0;
        zeta2 = 1.0;
        zeta7 = 1.0;
        zeta8 = 1.0;
    }

    Dr = Fz * R0 *
             ((p->QDZ6 + p->QDZ7 * dfz) * p->LRES * zeta2 +
              ((p->QDZ8 + p->QDZ9 * dfz) * (1.0 + p->PPZ2 * dpi) + (p->QDZ10 + p->QDZ11 * dfz) * fabs(gamma_star)) *
                  gamma_star * p->LKZC * zeta0) *
             b->LMUY_star * sgn(c->Vx) * cos(alpha_star) +
         zeta8 - 1.0; /* eq 4.E47 */
    Br = (p->QBZ9 * p->LKY / b->LMUY_star + p->QBZ10 * lat->By * lat->Cy) * z6; /* eq 4.E45 */
    a->alphar = alphar; a->alphat = alphat; a->Dr = Dr; a->Cr = zeta7; a->Cr_im = zeta7_im; /* 4.E46 */
    a->Br = Br; a->Dt = Dt; a->Ct = Ct; a->Bt = Bt; a->Et = Et; a->Kya_prime = Kya_prime;
}

/* Dr*cos(Cr*u) with a possibly complex Cr = Cr_re + i*Cr_im, real part: Re cos(x + iy) = cos(x)*cosh(y)
 * (the real part of the C99 complex cosine, computed as this product). */
MF_FN double residual(double Dr, double Cr_re, double Cr_im, double u, double factor)
{
    if (Cr_im == 0.0) return Dr * cos(Cr_re * u) * factor;
    return Dr * (cosh(Cr_im * u) * cos(Cr_re * u)) * factor;
}

/* PAC2002 pure-slip aligning moment (mftire.mf.pac2002.mz0): Mz0 = -t*Fy0 + Mzr with Fy0 at the
   actual camber (Pacejka 2006 eqs 4.E31, 4.E32) and cos(alpha) once in Mzr (inside Dr, eq 4.E36). */
MF_FN void mz0_pac2002(const Cond *c, const Basic *b, const AlignTerms *a, const PureLat *lat, double *Mz,
                        double *t_out, double *Mzr_out)
{
    double t0 = trail_mf(a->Dt, a->Ct, a->Bt, a->Et, a->alphat, b->alpha_prime) * c->smooth; /* eq 4.E33 */
    double Mzr0 = residual(a->Dr, a->Cr, a->Cr_im, atan(a->Br * a->alphar), 1.0) * c->smooth;          /* eq 4.E36 */
    *Mz = -t0 * lat->Fy0 + Mzr0;
    *t_out = t0;
    *Mzr_out = Mzr0;
}

/* Pure-slip aligning moment (eqs 4.E31-4.E36): Mz0, t0, Mzr0. */
MF_FN void mz0(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, const AlignTerms *a, double *Mz,
                double *t_out, double *Mzr_out)
{
    PureLat lat0;
    double t0, Mzr0;
    if (is_pac2002(p)) { /* PAC2002: Fy0 at the actual camber (mz0_pac2002) */
        fy0(p, m, c, b, b->gamma_star, m->turn_slip, MF_W_EY, &lat0);
        mz0_pac2002(c, b, a, &lat0, Mz, t_out, Mzr_out);
        return;
    }
    fy0(p, m, c, b, 0.0, 0, MF_W_EY0, &lat0); /* Fy0 at gamma = phi = 0 */
    t0 = trail_mf(a->Dt, a->Ct, a->Bt, a->Et, a->alphat, b->alpha_prime) * c->smooth; /* eq 4.E33 */
    Mzr0 = residual(a->Dr, a->Cr, a->Cr_im, atan(a->Br * a->alphar), cos(b->alpha_prime)) * c->smooth; /* 4.E36 */
    *Mz = -t0 * lat0.Fy0 + Mzr0; /* eqs 4.E32, 4.E31 */
    *t_out = t0;
    *Mzr_out = Mzr0;
}

/* Combined-slip aligning moment (eqs 4.E71-4.E78; Besselink 2010 A54-A56). */
MF_FN void mz_combined(const MFParams *p, Ctx *m, const Cond *c, const Basic *b, const AlignTerms *a, double Kxk,
                        double Fx, double Fy, double Gyk, const PureLat *lat, double *Mz_out, double *t_out,
                        double *Mzr_out)
{
    double R0 = p->UNLOADED_RADIUS, ratio2, alphar_eq, alphat_eq, s, Mzr, Fy_prime, t, Mz;
    PureLat lat0;
    ratio2 = sq(Kxk / a->Kya_prime) * sq(c->kappa);
    /* MFeval departure: Besselink 2010 A54/A55 (tan inside) instead of book 4.E77/4.E78. */
    alphar_eq = atan(sqrt(sq(tan(a->alphar)) + ratio2)) * sgn(a->alphar); /* A54 */
    alphat_eq = atan(sqrt(sq(tan(a->alphat)) + ratio2)) * sgn(a->alphat); /* A55 */
    /* MFeval departure: A56 uses FNOMIN where book eq 4.E76 has Fz0'.  PAC2002 branch (issue 16, wildtir2):
       PAC2002 follows the book, s with Fz0' = LFZO*FNOMIN (mftire.mf.aligning.mz_combined). */
    s = R0 * (p->SSZ1 + p->SSZ2 * (Fy / (is_pac2002(p) ? p->LFZO * p->FNOMIN : p->FNOMIN)) +
              (p->SSZ3 + p->SSZ4 * b->dfz) * c->gamma) * p->LS; /* A56, 4.E76 */
    Mzr = residual(a->Dr, a->Cr, a->Cr_im, atan(a->Br * alphar_eq), 1.0); /* eq 4.E75 */

    /* Fy at zero camber (and zero spin weighting) for the trail term, eq 4.E74; the pure
       lateral force at the actual inclination is that force when the inclination is zero. */
    if (lat != NULL && (m->batch_camber < 0 ? b->gamma_star == 0.0 : m->batch_camber == 0)) {
        lat0 = *lat;
    } else {
        fy0(p, m, c, b, 0.0, m->turn_slip, MF_W_EY0, &lat0);
    }
    Fy_prime = Gyk * lat0.Fy0; /* eq 4.E74; Gyk does not depend on muy or zeta2 */
    /* MFeval departure: t is multiplied by LFZO, as TNO's solver does (not in PAC2002). */
    t = trail_mf(a->Dt, a->Ct, a->Bt, a->Et, alphat_eq, b->alpha_prime) * (is_pac2002(p) ? 1.0 : p->LFZO); /* 4.E73 */
    t = t * c->smooth;
    Mzr = Mzr * c->smooth;
    if (is_pac2002(p) && lat != NULL) {
        /* PAC2002 (Pacejka 2006 eqs 4.E71, 4.E74): F'y = Fy - SVyk = Gyk*Fy0, Fy0 with camber. */
        Mz = -t * (Gyk * lat->Fy0) + Mzr + s * Fx;
    } else if (is_mf52(p)) {
        /* MF 5.2 (TNO equation manual): kappa-induced side force excluded from the trail term. */
        double dfz = b->dfz, gamma_star = b->gamma_star, DVyk, SVyk;
        DVyk = lat0.muy * c->Fz * (p->RVY1 + p->RVY2 * dfz + p->RVY3 * gamma_star) *
               cos_atan(p->RVY4 * b->alpha_star); /* eq 4.E67 at zeta2 = 1 */
        SVyk = DVyk * sin(p->RVY5 * atan(p->RVY6 * c->kappa)) * p->LVYKA * c->smooth; /* eq 4.E66 */
        Mz = -t * (Fy - SVyk) + Mzr + s * Fx;
    } else {
        Mz = -t * Fy_prime + Mzr + s * Fx; /* eqs 4.E72, 4.E71 */
    }
    *Mz_out = Mz;
    *t_out = t;
    *Mzr_out = Mzr;
}

/* ------------------------------------------------------------------ overturning.py */

/*
 * Overturning moment Mx [N m].
 * MFeval departure: book eq 4.E69 and paper eq A47 do not match TNO's solver; the
 * draft of Besselink et al. (2010), eq 49, with QSX12-QSX14 does.  Below FZMIN the
 * load is reduced as Fz*(Fz/FZMIN)^2 (found empirically by the reference's author).
 */
MF_FN double mx(const MFParams *p, const Cond *c, double dpi, double Fy)
{
    double Fz = c->Fz, FZMIN = p->FZMIN, R0 = p->UNLOADED_RADIUS, Fz0 = p->FNOMIN, g = c->gamma;
    if (Fz < FZMIN) Fz = Fz * sq(Fz / FZMIN);
    return R0 * Fz * p->LMX *
               (p->QSX1 * p->LVMX - p->QSX2 * g * (1.0 + p->PPMX1 * dpi) - p->QSX12 * g * fabs(g) +
                p->QSX3 * Fy / Fz0 +
                p->QSX4 * cos(p->QSX5 * atan(sq(p->QSX6 * Fz / Fz0))) *
                    sin(p->QSX7 * g + p->QSX8 * atan(p->QSX9 * Fy / Fz0)) +
                p->QSX10 * atan(p->QSX11 * Fz / Fz0) * g) +
           R0 * Fy * p->LMX * (p->QSX13 + p->QSX14 * fabs(g)); /* draft eq 49 */
}

/* ------------------------------------------------------------------ rolling.py */

/*
 * Rolling-resistance moment My [N m], negative when rolling forward (ISO).
 * MFeval departure: book eq 4.E70 gives the wrong sign and scales by Fz; paper eq
 * A48 (scaled by FNOMIN) is used.  The reference's empirical low-load reduction
 * Fz*(Fz/FZMIN) and its low-speed treatment (a sine ramp over slips near lock,
 * sign change beyond) are reproduced.  Uses the load and slip as given (unlimited).
 */
MF_FN double my(const MFParams *p, const Cond *c, double Fx)
{
    double Fz = c->uFz, FZMIN = p->FZMIN, Vx = c->Vx, kappa = c->ukappa;
    double R0 = p->UNLOADED_RADIUS, Fz0 = p->FNOMIN, V0 = p->LONGVL, vr, My, high, low;
    if (Fz < FZMIN) Fz = Fz * (Fz / FZMIN);
    vr = Vx / V0;
    if (is_mf52(p)) {
        /* MF 5.2 (TNO equation manual) */
        My = -R0 * Fz * p->LMY * (p->QSY1 + p->QSY2 * (Fx / Fz0) + p->QSY3 * fabs(vr) + p->QSY4 * pow(vr, 4.0));
    } else {
        My = -R0 * Fz0 * p->LMY *
             (p->QSY1 + p->QSY2 * (Fx / Fz0) + p->QSY3 * fabs(vr) + p->QSY4 * pow(vr, 4.0) +
              (p->QSY5 + p->QSY6 * (Fz / Fz0)) * sq(c->gamma)) *
             (pow(Fz / Fz0, p->QSY7) * pow(c->P / p->NOMPRES, p->QSY8)); /* A48 */
    }
    if (Vx < 0.0) My = -My; /* driving backwards */
    high = p->VXLOW / fabs(Vx) - 1.0;
    low = -1.0 - p->VXLOW - high;
    if (kappa >= low && kappa <= high) {
        /* Linear interpolation from (kappa=-1, 0) to (kappa=high, pi/2), then sine. */
        double red = (0.0 * (high - kappa) + (MF_PI / 2) * (kappa + 1.0)) / (high + 1.0);
        My = My * sin(red);
    }
    if (kappa < low) My = -My;
    return (Vx == 0.0) ? 0.0 : My;
}

/* ------------------------------------------------------------------ vertical.py (loaded radius) */

/* Linear load-deflection coefficient Q_FZ1 from VERTICAL_STIFFNESS (Besselink 2010 eq 4). */
MF_FN double q_fz1(const MFParams *p)
{
    return sqrt(sq(p->VERTICAL_STIFFNESS * p->UNLOADED_RADIUS / p->FNOMIN) - 4.0 * p->Q_FZ2);
}

/*
 * MF 6.1 deflection, loaded radius and vertical stiffness (eq A3.3):
 * Fz = (Q_FZ2*(rho/R0)^2 + Q_FZ1*(rho/R0))*(1 + Q_V2*R0/V0*|omega| - (Q_FCX*Fx/Fz0)^2
 * - (Q_FCY*Fy/Fz0)^2)*(1 + PFZ1*dpi)*Fz0 solved for rho in closed form.
 */
MF_FN void loaded_radius_61(const MFParams *p, const Cond *c, double dpi, double omega, double Romega, double Fx,
                             double Fy, double *rho_out, double *Rl_out, double *Cz_out)
{
    double Fz = c->Fz_low, R0 = p->UNLOADED_RADIUS, Fz0 = p->FNOMIN, V0 = p->LONGVL;
    double speed = p->Q_V2 * (R0 / V0) * fabs(omega);
    double ext = (1.0 + speed - sq(p->Q_FCX * Fx / Fz0) - sq(p->Q_FCY * Fy / Fz0)) * (1.0 + p->PFZ1 * dpi) * Fz0;
    double A = p->Q_FZ2, B = q_fz1(p), C = -(Fz / ext);
    double x = (-B + sqrt(sq(B) - 4.0 * A * C)) / (2.0 * A);
    double rho = max_num(x * R0, 0.0); /* NaN (Q_FZ2 = 0) gives 0, as max() in the reference */
    double Rl = max_num(Romega - rho, 0.0); /* Pacejka 2012 eq A3.2 */
    if (Fz == 0.0) rho = 1e-6;
    *rho_out = rho;
    *Rl_out = Rl;
    *Cz_out = Fz / rho;
}

/* Whether the file's loaded radius has the closed form of MF 6.1: FITTYP 61 and PAC2002 (whose
 * MF 6.2 equation reduces to it); MF 5.2 and 6.2 files solve the MF 6.2 equation (below). */
MF_FN int radius_closed_form(const MFParams *p) { return p->FITTYP == 61.0 || is_pac2002(p); }

/* MF 6.2 vertical force for a given loaded radius (MF-Tyre/MF-Swift 6.2 manual). */
MF_FN double vertical_force_62(const MFParams *p, double gamma, double abs_tan_gamma, double omega, double Romega,
                                double dpi, double Rl, double Fx, double Fy, double qfz1, double *rho_out)
{
    double R0 = p->UNLOADED_RADIUS, Fz0 = p->FNOMIN, V0 = p->LONGVL;
    double ratio = Rl / Romega;
    double Sfyg = (p->Q_FYS1 + p->Q_FYS2 * ratio + p->Q_FYS3 * sq(ratio)) * gamma;
    double rho_fr = max_num(Romega - Rl, 0.0);
    double rtw = (1.075 - 0.5 * p->ASPECT_RATIO) * p->WIDTH; /* reference tread width */
    double q1 = p->Q_CAM1, q2 = p->Q_CAM2, rho_g, rho, fcorr;
    rho_g = sq((q1 * Rl + q2 * sq(Rl)) * gamma) * (rtw / 8.0) * abs_tan_gamma /
                sq((q1 * Romega + q2 * sq(Romega)) * gamma) -
            p->Q_CAM3 * rho_fr * fabs(gamma);
    if (isnan(rho_g)) rho_g = 0.0;
    rho = max_num(rho_fr + rho_g, 0.0);
    fcorr = (1.0 + p->Q_V2 * (R0 / V0) * fabs(omega) - sq(p->Q_FCX * Fx / Fz0) -
             sq(pow(rho / R0, p->Q_FCY2) * (p->Q_FCY * (Fy - Sfyg) / Fz0))) *
            (1.0 + p->PFZ1 * dpi);
    *rho_out = rho;
    return fcorr * (qfz1 * (rho / R0) + p->Q_FZ2 * sq(rho / R0)) * Fz0;
}

/*
 * MF 6.2 loaded radius: the root of vertical_force_62(Rl) = Fz in [0, Romega], by a
 * bracketed Newton iteration (bisection whenever a Newton step leaves the bracket)
 * to a force residual of 1e-9*Fz.  Where no root lies in [0, Romega], Rl = Romega.
 * In pieces (start, step, finish) so that the array kernel can run the steps of many points
 * side by side; loaded_radius_62 puts them together.
 */
typedef struct {
    double target, g, atg, omega, Romega, dpi, Fx, Fy; /* the equation's fixed arguments (8: arrays of them
                                                          vectorise in the array kernel) */
} Root62;
/* The search's state: the iterate x, the bracket [lo, hi] and no_root (1.0 when no root lies in
 * [0, Romega]), kept apart so that the array kernel holds them in lanes. */

#define MF_ROOT62_STEPS 60 /* iterations at most */

/* vertical_force_62(Rl) - Fz [N] */
MF_FN double root62_residual(const MFParams *p, const Root62 *r, double Rl)
{
    double rho;
    return vertical_force_62(p, r->g, r->atg, r->omega, r->Romega, r->dpi, Rl, r->Fx, r->Fy, q_fz1(p), &rho) -
           r->target;
}

MF_FN void root62_start(const MFParams *p, const Cond *c, double dpi, double omega, double Romega, double Fx,
                        double Fy, Root62 *r, double *lo, double *hi, double *x, double *no_root)
{
    double rho0, Rl0, Cz0;
    r->target = c->Fz;
    r->g = c->gamma;
    r->atg = fabs(tan(c->gamma)); /* |tan(gamma)| of vertical_force_62, constant over the iteration */
    r->omega = omega;
    r->Romega = Romega;
    r->dpi = dpi;
    r->Fx = Fx;
    r->Fy = Fy;
    *lo = 0.0;
    *hi = Romega;
    /* Force at zero free deflection already >= target (camber deflection only).  NaN
     * (0*inf when Q_FCY2 < 0 and rho = 0) counts as below target. */
    *no_root = root62_residual(p, r, Romega) >= 0.0;
    /* start from the MF 6.1 closed form without camber and force terms */
    loaded_radius_61(p, c, dpi, omega, Romega, 0.0, 0.0, &rho0, &Rl0, &Cz0);
    *x = clip(Romega - rho0, 0.0, Romega);
}

/* One iteration: returns 0 when the search has ended (converged, or no root). */
MF_FN int root62_step(const MFParams *p, const Root62 *r, double no_root, double *lo, double *hi, double *x)
{
    const double h = 1e-7, tol_f = 1e-9 * (r->target > 1.0 ? r->target : 1.0); /* [N] */
    double fx = root62_residual(p, r, *x), dfx, x_new;
    if (fx > 0.0) *lo = *x; else *hi = *x;
    if (fabs(fx) <= tol_f || no_root != 0.0) return 0;
    dfx = (root62_residual(p, r, *x + h) - fx) / h;
    x_new = *x - fx / dfx;
    if ((x_new < *lo) || (x_new > *hi) || !isfinite(x_new)) x_new = 0.5 * (*lo + *hi);
    *x = x_new;
    return 1;
}

MF_FN void root62_finish(const MFParams *p, const Root62 *r, double no_root, double x, double *rho_out,
                         double *Rl_out, double *Cz_out)
{
    double rho, Rl = no_root != 0.0 ? r->Romega : x;
    vertical_force_62(p, r->g, r->atg, r->omega, r->Romega, r->dpi, Rl, r->Fx, r->Fy, q_fz1(p), &rho);
    if (r->target == 0.0) rho = 1e-6;
    *rho_out = rho;
    *Rl_out = Rl;
    *Cz_out = r->target / rho;
}

MF_FN void loaded_radius_62(const MFParams *p, const Cond *c, double dpi, double omega, double Romega, double Fx,
                            double Fy, double *rho_out, double *Rl_out, double *Cz_out)
{
    Root62 r;
    double lo, hi, x, no_root;
    int i;
    root62_start(p, c, dpi, omega, Romega, Fx, Fy, &r, &lo, &hi, &x, &no_root);
    for (i = 0; i < MF_ROOT62_STEPS; i++)
        if (!root62_step(p, &r, no_root, &lo, &hi, &x)) break;
    root62_finish(p, &r, no_root, x, rho_out, Rl_out, Cz_out);
}

/* Deflection rho, loaded radius Rl and vertical stiffness Cz of the file's model: the closed form
 * (MF 6.1, PAC2002) or the root of the MF 6.2 equation (MF 5.2, 6.2). */
MF_FN void loaded_radius(const MFParams *p, const Ctx *m, const Cond *c, double dpi, double Romega, double Fx,
                         double Fy, MFOutputs *out)
{
    if (m->closed_radius || radius_closed_form(p))
        loaded_radius_61(p, c, dpi, c->omega, Romega, Fx, Fy, &out->rho, &out->Rl, &out->Cz);
    else
        loaded_radius_62(p, c, dpi, c->omega, Romega, Fx, Fy, &out->rho, &out->Rl, &out->Cz);
}

/*
 * Contact-patch half length a and half width b [m] (Besselink 2010 eqs 9, 10).
 * Uses the load as given; beyond rim bottoming the load is held at the bottoming
 * load (empirical rule of the reference evaluator).
 */
MF_FN void contact_patch(const MFParams *p, const Cond *c, double dpi, double *a_out, double *b_out)
{
    double R0 = p->UNLOADED_RADIUS, w = p->WIDTH, Fz0 = p->FNOMIN;
    double NCz = p->VERTICAL_STIFFNESS * (1.0 + p->PFZ1 * dpi); /* Besselink 2010 eq 5 */
    double Fz = c->uFz, Rl_approx = R0 - Fz / NCz;
    if (Rl_approx - (p->RIM_RADIUS + p->BOTTOM_OFFST) < 0.0) Fz = (R0 - p->RIM_RADIUS - p->BOTTOM_OFFST) * NCz;
    if (is_mf52(p)) {
        double QA1 = p->Q_A1, QA2 = p->Q_A2;
        if (QA1 == 0.0 && QA2 == 0.0) {
            /* Defaults of the reference evaluator when the MF 5.2 file has none. */
            double y = log10(R0 * (p->VERTICAL_STIFFNESS / Fz0));
            QA1 = -0.0388 * pow(y, 3.0) + 0.2509 * sq(y) + -0.6283 * y + 0.6279;
            QA2 = 1.693 * sq(QA1);
        }
        *a_out = R0 * (QA2 * (Fz / Fz0) + QA1 * sqrt(Fz / Fz0)); /* MF 5.2 manual */
        *b_out = w / 2.0;
    } else {
        double f = Fz / (NCz * R0);
        *a_out = R0 * (p->Q_RA2 * f + p->Q_RA1 * sqrt(f)); /* Besselink 2010 eq 9 */
        *b_out = w * (p->Q_RB2 * f + p->Q_RB1 * pow(f, 1.0 / 3.0)); /* Besselink 2010 eq 10 */
    }
}

/* ------------------------------------------------------------------ relaxation.py */

/* Carcass stiffnesses and relaxation lengths (Besselink et al. 2010 eqs 17-19). */
MF_FN void relaxation(const MFParams *p, const Cond *c, double Kxk, double Kya, double *Cx_out, double *Cy_out,
                       double *sx_out, double *sy_out)
{
    double Fz0 = p->FNOMIN, R0 = p->UNLOADED_RADIUS, Fz0p = mf_fz0p(p); /* eq 4.E1 */
    double dfz = mf_dfz(p, c->Fz); /* eq 4.E2a */
    double dpi = mf_dpi(p, c->P); /* eq 4.E2b */
    double Cx = p->LONGITUDINAL_STIFFNESS * (1.0 + p->PCFX1 * dfz + p->PCFX2 * sq(dfz)) * (1.0 + p->PCFX3 * dpi); /* 17 */
    double Cy = p->LATERAL_STIFFNESS * (1.0 + p->PCFY1 * dfz + p->PCFY2 * sq(dfz)) * (1.0 + p->PCFY3 * dpi); /* 18 */
    if (is_mf52(p)) {
        /* MF 5.2 relaxation lengths (TNO equation manual) */
        *sx_out = (p->PTX1 + p->PTX2 * dfz) * exp(-p->PTX3 * dfz) * p->LSGKP * R0 * c->Fz / Fz0;
        *sy_out = p->PTY1 * sin(2.0 * atan(c->Fz / (p->PTY2 * Fz0p))) * (1.0 - p->PKY3 * fabs(c->gamma)) * R0 *
                  p->LFZO * p->LSGAL;
    } else {
        *sx_out = fabs(Kxk / Cx); /* eq 19 */
        *sy_out = fabs(Kya / Cy); /* eq 19 */
    }
    *Cx_out = Cx;
    *Cy_out = Cy;
}

/* ------------------------------------------------------------------ extensions.py */

/*
 * Model extensions of the [MFTIRE_EXTENSIONS] section (mftire/mf/extensions.py): each term
 * multiplies MF scaling factors by f(variable) or adds a force offset Fz*(f - 1).
 * mf_ext_gen.h (included at the top, through the interface mf_ext.h) is GENERATED by
 * mftire/mf/cheaders.py from mftire.mf.extensions: the term table MF_TERMS (targets, form,
 * variables, coefficient fields of MFParams), the variable function mf_ext_var and the form
 * function mf_ext_form (the C expression of each mftire.mf.extensions.Form).  This loop is the
 * only hand-written part.
 */

/* The term table: MF_TERMS of mf_ext_gen.h in an FMU; data given at run time in the array
 * kernel (mf_kernel.c, whose mf_ext_gen.h defines MF_EXT_RUNTIME and the MFTerm layout). */
typedef struct {
#if MF_N_TERMS > 0 || defined(MF_EXT_RUNTIME)
    const MFTerm *terms;
#else
    const void *terms;
#endif
    int n;
} ExtTable;

#if MF_N_TERMS > 0 || defined(MF_EXT_RUNTIME)
/* The value of the table form: c holds the n levels (any order), then the n values; linear between the
 * levels bracketing u, the value of the end level beyond them (numpy: np.interp of each value's hat weight,
 * mftire.mf.extensions._table).  NaN gives NaN. */
MF_FN double mf_ext_table(double u, const double *c, int n)
{
    int k, lo = -1, hi = -1;
    double w;
    if (u != u) return u;
    for (k = 0; k < n; k++) {
        if (c[k] <= u && (lo < 0 || c[k] > c[lo])) lo = k;
        if (c[k] >= u && (hi < 0 || c[k] < c[hi])) hi = k;
    }
    if (lo < 0) return c[n + hi];
    if (hi < 0 || c[hi] == c[lo]) return c[n + lo];
    w = (u - c[lo]) / (c[hi] - c[lo]);
    return c[n + lo] * (1.0 - w) + c[n + hi] * w;
}

/* q = p with the targeted scaling factors multiplied by f; off[0], off[1] the FX/FY offset sums; off[2],
 * off[3] the slip-angle and camber offsets, off[4] the pressure factor and off[5] the longitudinal-slip
 * offset of the input laws (extensions.py INPUT_TARGETS).
 * The term fields are read as doubles from p's storage at the indices of the table (in the
 * array kernel the storage runs on past MFParams with the numbers of the terms). */
MF_FN void apply_extensions(const ExtTable *ext, const MFParams *p, Ctx *m, const Cond *c, const double *data,
                             MFParams *q, double *off)
{
    const double *P = (const double *)p;
    double *Q = (double *)q;
    int i, k;
    *q = *p;
    off[0] = off[1] = off[2] = off[3] = off[5] = 0.0;
    off[4] = 1.0;
    for (i = 0; i < ext->n; i++) {
        const MFTerm *t = &ext->terms[i];
        /* modes 1xx: the variables clamped to the range the term was fitted on, with a warning */
        double u = mf_ext_var(t->var, p, c, data), z, z2 = 0.0, f;
        if (m->limits) {
            if (u < P[t->min] || u > P[t->max]) flag(m, MF_W_EXT_RANGE);
            u = clip(u, P[t->min], P[t->max]);
        }
        z = (u - P[t->ref]) / P[t->scale];
        if (t->var2 >= 0) {
            double u2 = mf_ext_var(t->var2, p, c, data);
            if (m->limits) {
                if (u2 < P[t->min2] || u2 > P[t->max2]) flag(m, MF_W_EXT_RANGE);
                u2 = clip(u2, P[t->min2], P[t->max2]);
            }
            z2 = (u2 - P[t->ref2]) / P[t->scale2];
        }
        f = mf_ext_form(t->form, u, z, z2, P[t->ref], P + t->c0, t->n);
        for (k = 0; k < t->n_targets; k++) {
            if (t->targets[k] == MF_TARGET_FX_OFFSET) off[0] += f - 1.0;
            else if (t->targets[k] == MF_TARGET_FY_OFFSET) off[1] += f - 1.0;
            else if (t->targets[k] == MF_TARGET_ALPHA_OFFSET) off[2] += f - 1.0;
            else if (t->targets[k] == MF_TARGET_GAMMA_OFFSET) off[3] += f - 1.0;
            else if (t->targets[k] == MF_TARGET_P_FACTOR) off[4] *= f;
            else if (t->targets[k] == MF_TARGET_KAPPA_OFFSET) off[5] += f - 1.0;
            else Q[t->targets[k]] *= f;
        }
    }
}
#endif

/* ------------------------------------------------------------------ solver.py */

MF_FN double clean(Ctx *m, int kind, double x, double fill)
{
    if (!isfinite(x)) { /* an infinite input is treated as NaN (mftire.mf.solver._clean) */
        flag(m, kind);
        return fill;
    }
    return x;
}

/* Decode a checked useMode into the context. */
MF_FN void decode_mode(Ctx *m, int use_mode)
{
    m->limits = use_mode / 100 == 1;
    m->alpha_star = (use_mode / 10) % 10 == 2;
    m->turn_slip = use_mode % 10 == 2;
    m->combined = use_mode % 10 != 0;
    m->closed_radius = 0;
}

/* The data variables of the model extensions (MFInputs.data) with NaN replaced by 0 and a warning. */
MF_FN void clean_data(Ctx *m, const MFInputs *in, double *data)
{
    int k;
    for (k = 0; k < MF_MAX_DATA; k++) data[k] = 0.0;
#if MF_N_DATA > 0
    for (k = 0; k < MF_N_DATA; k++) data[k] = clean(m, MF_W_NAN_DATA0 + k, in->data[k], 0.0);
#endif
    (void)m;
    (void)in;
}

/*
 * Piece 1 of solver.py without the wheel spin: NaN inputs replaced by 0 (pressure: INFLPRES)
 * with a warning, then the input stage (condition_inputs).  Returns dpi (eq 4.E2b).
 */
MF_FN double prepare_point(const MFParams *p, Ctx *m, const MFInputs *in, Cond *c)
{
    double Fz, kappa, alpha, gamma, phit, Vx, P;
    Fz = clean(m, MF_W_NAN_FZ, in->Fz, 0.0);
    kappa = clean(m, MF_W_NAN_KAPPA, in->kappa, 0.0);
    alpha = clean(m, MF_W_NAN_ALPHA, in->alpha, 0.0);
    gamma = clean(m, MF_W_NAN_GAMMA, in->gamma, 0.0);
    phit = clean(m, MF_W_NAN_PHIT, in->phit, 0.0);
    Vx = clean(m, MF_W_NAN_VX, in->Vx, 0.0);
    P = in->P;
    if (!isfinite(P) || P <= 0.0) P = p->INFLPRES;
    condition_inputs(p, m, Fz, kappa, alpha, gamma, phit, Vx, P, c);
    return mf_dpi(p, c->P); /* eq 4.E2b */
}

/* What mf_channels computes: the MF_WANT_* bits of mf_eval.h (mftire.mf.solver.channels, outputs). */

/*
 * Pieces 2 and 3 of solver.py for one conditioned point c (c->omega filled): the model
 * extensions, turn slip, the channels of want (what they need is computed too) and the
 * outputs that depend on them.  Fields of out that are not wanted are left untouched.
 */
MF_FN void mf_channels(const MFParams *p, Ctx *m, const ExtTable *ext, Cond *c, double dpi, double Romega,
                        const double *data, double muRoad, unsigned want, MFOutputs *out)
{
    Basic b;
    PureLat lat;
    AlignTerms at;
    double z1, Fx0, mux = 0.0, Kxk = 0.0, Fy_comb, Gyk = 0.0, Fx = 0.0, Fy = 0.0;
    /* force offsets of the model extensions (factors of Fz), input laws (alpha, gamma offsets, P factor,
     * kappa offset) */
    double off[6] = {0.0, 0.0, 0.0, 0.0, 1.0, 0.0};
    double dpi_mx = dpi; /* dpi of Mx: the effective pressure of an input law (the radius keeps dpi) */
    int need_fx = (want & MF_NEEDS_FX) != 0;
    int need_fy = (want & MF_NEEDS_FY) != 0;
#if MF_N_TERMS > 0 || defined(MF_EXT_RUNTIME)
    MFParams q; /* p with the extension terms applied to its scaling factors */
    Cond ce; /* c with the input laws applied (extensions.py apply_input_laws) */
    if (ext->n > 0) {
        apply_extensions(ext, p, m, c, data, &q, off);
        p = &q;
        if (off[2] != 0.0 || off[3] != 0.0 || off[4] != 1.0 || off[5] != 0.0) {
            ce = *c;
            ce.alpha += off[2];
            ce.gamma += off[3];
            ce.kappa += off[5];
            ce.P *= off[4];
            dpi_mx = (ce.P - p->NOMPRES) / p->NOMPRES; /* eq 4.E2b */
            c = &ce;
        }
    }
#endif
    (void)ext;
    (void)data;
    if (m->turn_slip) turn_slip_spin(p, c);
    basic(p, m, c, muRoad, &b);
    lat.Kya = 0.0;

    if (need_fx) {
        z1 = m->turn_slip ? zeta1(p, b.dfz, c->kappa, c->phi) : 1.0;
        fx0(p, m, c, &b, z1, &Fx0, &mux, &Kxk);
        Fx = (m->combined ? fx_combined(p, m, c, &b, Fx0) : Fx0) + c->Fz * off[0];
        out->Fx = Fx; out->mux = mux; out->Kxk = Kxk;
    }
    if (need_fy) {
        fy0(p, m, c, &b, b.gamma_star, m->turn_slip, MF_W_EY, &lat);
        Fy_comb = fy_combined(p, m, c, &b, lat.Fy0, lat.muy, lat.zeta2, &Gyk);
        Fy = (m->combined ? Fy_comb : lat.Fy0) + c->Fz * off[1];
        out->Fy = Fy; out->muy = m->limits ? fabs(lat.muy) : lat.muy; out->Kya = lat.Kya;
    }
    if (want & MF_WANT_MZ) {
        aligning_terms(p, m, c, &b, &lat, Gyk, &at);
        if (m->combined)
            mz_combined(p, m, c, &b, &at, Kxk, Fx, Fy, Gyk, &lat, &out->Mz, &out->t, &out->Mzr);
        else
            mz0(p, m, c, &b, &at, &out->Mz, &out->t, &out->Mzr);
    }
    if (want & MF_WANT_MX) out->Mx = mx(p, c, dpi_mx, Fy);
    if (want & MF_WANT_MY) out->My = my(p, c, Fx);
    if (want & MF_WANT_RAD) loaded_radius(p, m, c, dpi, Romega, Fx, Fy, out);
    if (want & MF_WANT_PATCH) {
        double a, bw;
        contact_patch(p, c, dpi, &a, &bw);
        out->a2 = 2.0 * a;
        out->b2 = 2.0 * bw;
    }
    if (want & MF_WANT_RELAX) {
        /* the relaxation lengths need the slip stiffnesses only (Besselink 2010 eq 19) */
        if (!need_fx) Kxk = kxk(p, c->Fz, b.dfz, b.dpi); /* eq 4.E15 */
        if (!need_fy) {
            double z2 = 1.0, z3 = 1.0;
            if (m->turn_slip) zeta2_zeta3(p, b.dfz, c->alpha, c->phi, &z2, &z3);
            lat.Kya = kya(p, c->Fz, b.Fz0p, b.dpi, b.gamma_star, z3); /* eq 4.E25 */
        }
        relaxation(p, c, Kxk, lat.Kya, &out->Cx, &out->Cy, &out->sigmax, &out->sigmay);
        /* the slip stiffnesses and friction coefficients too (cheap; the transient model's sliding limit) */
        if (!need_fx) {
            out->Kxk = Kxk;
            out->mux = mu_x(p, c, &b);
        }
        if (!need_fy) {
            double muy = mu_y(p, &b, b.gamma_star);
            out->Kya = lat.Kya;
            out->muy = m->limits ? fabs(muy) : muy;
        }
    }
}

int mf_evaluate(const MFParams *p, int use_mode, const MFInputs *in, MFOutputs *out, mf_warning_fn warn, void *ctx)
{
    return mf_evaluate_want(p, use_mode, in, MF_WANT_ALL, out, warn, ctx);
}

int mf_evaluate_want(const MFParams *p, int use_mode, const MFInputs *in, unsigned want, MFOutputs *out,
                     mf_warning_fn warn, void *ctx)
{
    char msg[256];
    unsigned long warnings;
    int k;
    if (mf_check_mode(use_mode, msg, sizeof msg) != MF_OK) return MF_BAD_MODE;
    if (mf_check_fittyp(p, msg, sizeof msg) != MF_OK) return MF_BAD_FITTYP;
    warnings = mf_evaluate_unchecked(p, use_mode, in, want, out);
    if (warn && warnings)
        for (k = 0; k < MF_W_COUNT; k++)
            if (warnings & (1UL << k)) {
                char text[200];
                mf_warning_text(p, k, text, sizeof text);
                warn(ctx, k, text);
            }
    return MF_OK;
}

unsigned long mf_evaluate_unchecked(const MFParams *p, int use_mode, const MFInputs *in, unsigned want,
                                    MFOutputs *out)
{
    Ctx m;
    Cond c;
    double dpi, Re, Romega, omega, omega_in;
    double data[MF_MAX_DATA] = {0.0};
    int omega_given, kmax = 100;
#if MF_N_TERMS > 0
    ExtTable ext = {MF_TERMS, MF_N_TERMS};
#else
    ExtTable ext = {NULL, 0};
#endif

    m.warnings = 0;
    m.batch_camber = -1;
    decode_mode(&m, use_mode);
    clean_data(&m, in, data);
    dpi = prepare_point(p, &m, in, &c);
    /* omega = 0 means "not given" (estimated); NaN is cleaned to a given 0 as in Python */
    omega_given = in->omega != 0.0;
    omega_in = omega_given ? clean(&m, MF_W_NAN_OMEGA, in->omega, 0.0) : 0.0;
    effective_rolling_radius(p, &c, dpi, omega_given, omega_in, &kmax, &Re, &Romega, &omega);
    c.omega = omega;
    mf_channels(p, &m, &ext, &c, dpi, Romega, data, in->muRoad, want, out);
    out->Fz = c.uFz; out->Re = Re; out->omega = c.omega;
    return m.warnings;
}
