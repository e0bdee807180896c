/*
 * mf_ext.h -- what the generated model-extension code (mf_ext_gen.h, mftire/mf/cheaders.py from
 * mftire.mf.extensions) may use of the evaluator mf_eval.c: the conditioned inputs of one point (Cond), the
 * load and pressure increments (eqs 4.E2a, 4.E2b: the builtin variables dfz and dpi) and the table form.
 * mf_ext_gen.h states its number of terms (MF_N_TERMS, MF_EXT_RUNTIME), then includes this header;
 * mf_eval.c includes mf_ext_gen.h at its top.  The generated code reads nothing else of the evaluator.
 *
 * MF_FN is the linkage mf_eval.c gives its functions (static, or always-inline in the array kernel): the
 * including file defines it first.
 */
#ifndef MF_EXT_H
#define MF_EXT_H

#include <math.h>   /* the forms' expressions */
#include <stddef.h> /* offsetof: MF_PIDX of the term table */

#include "mf_eval.h"

#ifndef MF_FN
#error "mf_ext.h: define MF_FN (the linkage of mf_eval.c's functions) before including it"
#endif

/* One operating point as the equations see it (mftire/mf/inputs.py: conditioned, low-speed reduced, clipped). */
typedef struct {
    double Fz;        /* vertical load [N], >= 0, <= FZMAX with limits */
    double Fz_low;    /* Fz raised to FZMIN (limits only) [N] */
    double kappa;     /* longitudinal slip, low-speed reduced and clipped */
    double alpha;     /* slip angle, low-speed reduced and clipped [rad] */
    double gamma;     /* inclination angle, clipped [rad] */
    double phit;      /* turn slip, conditioned [1/m] */
    double P;         /* inflation pressure, clipped [Pa] */
    double Vx;        /* forward speed (never limited) [m/s] */
    double uFz;       /* load as given (negative set to 0) [N] */
    double ukappa;    /* slip as given */
    double ukappa_low;
    double ualpha;
    double ugamma;
    int low_speed;
    double smooth;    /* low-speed smooth reduction factor, 1 where not low speed */
    double omega;     /* wheel spin [rad/s] */
    double phi;       /* turn-slip spin (eq 4.76) [1/m] */
    double eps_gamma; /* camber reduction factor epsilon_gamma (eq 4.90) */
} Cond;

/* Normalised load increment dfz = (Fz - Fz0')/Fz0', Fz0' = LFZO*FNOMIN (eqs 4.E1, 4.E2a). */
MF_FN double mf_dfz(const MFParams *p, double Fz);

/* Pressure increment dpi = (P - NOMPRES)/NOMPRES (eq 4.E2b). */
MF_FN double mf_dpi(const MFParams *p, double P);

#if MF_N_TERMS > 0 || defined(MF_EXT_RUNTIME) /* terms compiled in, or given at run time (mf_ext_gen.h) */
/* The table form: c holds the n levels, then the n values; linear between the levels bracketing u, the end
 * level's value beyond them. */
MF_FN double mf_ext_table(double u, const double *c, int n);
#endif

#endif /* MF_EXT_H */
