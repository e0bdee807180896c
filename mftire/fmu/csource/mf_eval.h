/*
 * mf_eval.h -- steady-state Magic Formula 6.1 / 6.2 (and MF 5.2, FITTYP 6) tyre
 * evaluator in plain C99, for the mftire FMU.
 *
 * The equations mirror mftire's Python evaluator (the modules of mftire/mf) line by line;
 * equation numbers refer to Pacejka (2012), "Tire and Vehicle Dynamics", 3rd ed.,
 * and Besselink, Schmeitz and Pacejka (2010), Vehicle System Dynamics 48:S1.
 * Axes are ISO-W (TYDEX W), units SI, angles in rad.
 *
 * MFParams (one double per .tir parameter) is generated from the FMU variable
 * table into mf_params.h by mftire/fmu/variables.py, together with the export-time
 * number of external variables of the model extensions ([MFTIRE_EXTENSIONS],
 * mftire/mf/extensions.py): MF_N_DATA and MF_DATA_NAMES (extra inputs, MFInputs.data).
 * The extension terms themselves are generated into mf_ext_gen.h.
 */
#ifndef MF_EVAL_H
#define MF_EVAL_H

#include "mf_params.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Room for the external variables of the model extensions (mftire.mf.extensions.MAX_EXTERNAL). */
#define MF_MAX_DATA 4

/* One operating point as the importer gives it. */
typedef struct {
    double Fz;     /* vertical load [N]; negative = lift-off (set to 0) */
    double kappa;  /* longitudinal slip [-] */
    double alpha;  /* slip angle [rad] */
    double gamma;  /* inclination angle [rad] */
    double phit;   /* turn slip [1/m] */
    double Vx;     /* forward speed [m/s] */
    double P;      /* inflation pressure [Pa]; NaN or <= 0 means INFLPRES */
    double omega;  /* wheel spin [rad/s]; 0 means "estimate from kappa, Vx, Re" */
    double muRoad; /* road friction factor multiplying LMUX and LMUY [-] */
    double data[MF_MAX_DATA]; /* data variables of the model extensions (MF_DATA_NAMES); NaN means 0 */
} MFInputs;

/* The outputs (the FMU publishes all but the last four). */
typedef struct {
    double Fx, Fy, Fz, Mx, My, Mz;
    double Re, Rl, rho, a2, b2, t, Mzr, mux, muy, Kxk, Kya, sigmax, sigmay;
    double omega, Cx, Cy, Cz;
} MFOutputs;

/* Warning kinds (bit numbers of the warning mask). */
enum {
    MF_W_NAN_FZ = 0, MF_W_NAN_KAPPA, MF_W_NAN_ALPHA, MF_W_NAN_GAMMA, MF_W_NAN_PHIT,
    MF_W_NAN_VX, MF_W_NAN_OMEGA,
    MF_W_ALPHA_LOW, MF_W_ALPHA_HIGH, MF_W_GAMMA_LOW, MF_W_GAMMA_HIGH,
    MF_W_FZ_HIGH, MF_W_FZ_LOW, MF_W_P_LOW, MF_W_P_HIGH, MF_W_KAPPA_LOW, MF_W_KAPPA_HIGH,
    MF_W_LOW_SPEED,
    MF_W_EX, MF_W_EY, MF_W_EXA, MF_W_EYK, MF_W_ET,
    MF_W_NAN_DATA0, MF_W_NAN_DATA1, MF_W_NAN_DATA2, MF_W_NAN_DATA3, /* NaN in MFInputs.data[0..3] */
    MF_W_EY0, /* Ey clipped in the zero-camber Fy0 of the aligning moment (a second warning, as in Python) */
    MF_W_EXT_RANGE, /* a model-extension variable outside its fitted range EXTn_MIN..MAX, clamped (modes 1xx) */
    MF_W_COUNT
};

/* The human-readable text of warning kind `kind` (for the limits: the file's limit value). */
void mf_warning_text(const MFParams *p, int kind, char *buf, unsigned long n);

/* Called once per distinct warning of an evaluation (kind, human-readable text). */
typedef void (*mf_warning_fn)(void *ctx, int kind, const char *message);

/* Return codes of mf_evaluate and the checks. */
#define MF_OK 0
#define MF_BAD_MODE 1
#define MF_BAD_FITTYP 2

/* Check a three-digit useMode; on failure write a message to msg (size n). */
int mf_check_mode(int use_mode, char *msg, unsigned long n);

/* Check that FITTYP is one the evaluator handles (6, 61, 62). */
int mf_check_fittyp(const MFParams *p, char *msg, unsigned long n);

/* Channel groups of mf_evaluate_want (what a group needs is computed too). */
#define MF_WANT_FX 1u     /* Fx, mux, Kxk */
#define MF_WANT_FY 2u     /* Fy, muy, Kya */
#define MF_WANT_MZ 4u     /* Mz, t, Mzr (needs FX, FY) */
#define MF_WANT_MX 8u     /* Mx (needs FY) */
#define MF_WANT_MY 16u    /* My (needs FX) */
#define MF_WANT_RAD 32u   /* rho, Rl, Cz (needs FX, FY) */
#define MF_WANT_PATCH 64u /* 2a, 2b */
#define MF_WANT_RELAX 128u /* Cx, Cy, sigmax, sigmay; Kxk, Kya, mux, muy (the slip stiffnesses and mu only) */
#define MF_WANT_ALL 255u
/* The groups whose channels need the whole longitudinal / lateral force computed. */
#define MF_NEEDS_FX (MF_WANT_FX | MF_WANT_MZ | MF_WANT_MY | MF_WANT_RAD)
#define MF_NEEDS_FY (MF_WANT_FY | MF_WANT_MZ | MF_WANT_MX | MF_WANT_RAD)

/*
 * Evaluate one operating point.  Returns MF_OK, or MF_BAD_MODE / MF_BAD_FITTYP
 * (then *out is untouched).  warn may be NULL.
 */
int mf_evaluate(const MFParams *p, int use_mode, const MFInputs *in, MFOutputs *out,
                mf_warning_fn warn, void *ctx);

/*
 * mf_evaluate for the channel groups of want only (MF_WANT_* bits; Fz, Re and omega always):
 * the fields of *out that no wanted group sets are left untouched.
 */
int mf_evaluate_want(const MFParams *p, int use_mode, const MFInputs *in, unsigned want, MFOutputs *out,
                     mf_warning_fn warn, void *ctx);

#ifdef __cplusplus
}
#endif
#endif /* MF_EVAL_H */
