/*
 * mf_eval.h -- steady-state Magic Formula 6.1 / 6.2 (and MF 5.2, FITTYP 6) tyre
 * evaluator in plain C99, for the mftire FMU.
 *
 * The equations mirror mftire's Python evaluator (the modules of mftire/mf) line by line;
 * equation numbers refer to Pacejka (2012), "Tire and Vehicle Dynamics", 3rd ed.,
 * and Besselink, Schmeitz and Pacejka (2010), Vehicle System Dynamics 48:S1.
 * Axes are ISO-W (TYDEX W), units SI, angles in rad.
 *
 * MFParams (one double per .tir parameter) is generated into mf_params.h by
 * mftire/mf/cheaders.py (from the FMU variable table, or the standard parameters for the
 * array kernel), together with the export-time
 * number of external variables of the model extensions ([MFTIRE_EXTENSIONS],
 * mftire/mf/extensions.py): MF_N_DATA and MF_DATA_NAMES (extra inputs, MFInputs.data).
 * The extension terms themselves are generated into mf_ext_gen.h.
 */
#ifndef MF_EVAL_H
#define MF_EVAL_H

#include "mf_params.h"
#include "mf_spec_gen.h" /* channel groups, warning kinds (generated from mftire/mf/spec.py) */

#ifdef __cplusplus
extern "C" {
#endif

/* Storage of the model's functions: empty (external) by default; an FMU, one translation unit, defines it
 * `static` so that only the FMI functions are external symbols (mftire/fmu/c/fmu_model.h). */
#ifndef MF_API
#define MF_API
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

/* The human-readable text of warning kind `kind` (for the limits: the file's limit value). */
MF_API void mf_warning_text(const MFParams *p, int kind, char *buf, unsigned long n);

/* Called once per distinct warning of an evaluation (kind, human-readable text). */
typedef void (*mf_warning_fn)(void *ctx, int kind, const char *message);

/* Return codes of mf_evaluate and the checks. */
#define MF_OK 0
#define MF_BAD_MODE 1
#define MF_BAD_FITTYP 2

/* Check a three-digit useMode; on failure write a message to msg (size n). */
MF_API int mf_check_mode(int use_mode, char *msg, unsigned long n);

/* Check that FITTYP is one the evaluator handles (MF_SPEC_FAMILIES). */
MF_API int mf_check_fittyp(const MFParams *p, char *msg, unsigned long n);

/*
 * Evaluate one operating point.  Returns MF_OK, or MF_BAD_MODE / MF_BAD_FITTYP
 * (then *out is untouched).  warn may be NULL.
 */
MF_API int mf_evaluate(const MFParams *p, int use_mode, const MFInputs *in, MFOutputs *out,
                mf_warning_fn warn, void *ctx);

/*
 * mf_evaluate for the channel groups of want only (MF_WANT_* bits; Fz, Re and omega always):
 * the fields of *out that no wanted group sets are left untouched.
 */
MF_API int mf_evaluate_want(const MFParams *p, int use_mode, const MFInputs *in, unsigned want, MFOutputs *out,
                     mf_warning_fn warn, void *ctx);

/*
 * mf_evaluate_want without its checks, for a caller that checks use_mode (mf_check_mode) and FITTYP
 * (mf_check_fittyp) when they are set, not at every evaluation (the FMU models): with a mode or FITTYP
 * those checks refuse, the numbers are undefined.  Returns the evaluation's warnings (bit 1UL << kind for
 * each MF_W_* kind), for the caller to report, writing a text (mf_warning_text) only when it shows it.
 */
MF_API unsigned long mf_evaluate_unchecked(const MFParams *p, int use_mode, const MFInputs *in, unsigned want,
                                           MFOutputs *out);

#ifdef __cplusplus
}
#endif
#endif /* MF_EVAL_H */
