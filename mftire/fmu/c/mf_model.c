/*
 * mf_model.c -- the steady-state tyre behind the FMI wrappers (fmu_model.h): mf_eval.c at the
 * importer's inputs, no continuous states.
 *
 * All variables are addressed through the value-reference table generated into
 * mf_model_gen.h from the Python variable table (mftire/fmu/variables.py).
 * Outputs are evaluated lazily: setting an input or a parameter marks the
 * instance dirty, reading an output evaluates once.
 */
#ifdef MF_FMU_UNITY /* a part of fmu.c (alone, for an importer that compiles every .c: nothing) */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_common.h"
#include "mf_model_gen.h"

/* The value-reference table (fmu_common.h). */
static const FMVarTable TABLE = {MF_VARS, MF_VAR_NAMES, MF_N_VARS};

/* Counters of the input/output guards: 9 inputs, MF_MAX_DATA data inputs, the outputs. */
#define MF_GUARD_SLOTS (9 + MF_MAX_DATA + 1)

struct FMModel {
    FMBase b; /* first: what every model keeps (fmu_common.h) */
    MFParams params;
    MFInputs inputs;
    MFOutputs outputs;
    int dirty;                        /* inputs or parameters changed since the last evaluation */
    FMWarnSlot guard[MF_GUARD_SLOTS]; /* input guards (9 inputs, data, outputs) */
};

static int update(FMModel *m);

static const char *fm_guid(void) { return MF_GUID; }
static size_t fm_size(void) { return sizeof(FMModel); }
static unsigned fm_n_states(void) { return 0; }
static int fm_is_unknown(unsigned vr) { return fm_var_is_unknown(&TABLE, vr); }
static unsigned fm_dependencies(unsigned *vrs, unsigned room) { return fm_var_dependencies(&TABLE, vrs, room); }

static void fm_reset(FMModel *m)
{
    m->params = MF_PARAM_START;
    m->inputs = MF_INPUT_START;
    memset(&m->outputs, 0, sizeof m->outputs);
    fm_base_reset(&m->b, MF_USEMODE_START);
    m->dirty = 1;
    memset(m->guard, 0, sizeof m->guard);
}

static int fm_exit_initialization(FMModel *m)
{
    if (fm_check_initialization(m->b.log, m->b.host, &m->params, m->b.use_mode, &TABLE) != FM_OK)
        return FM_ERROR;
    if (update(m) != FM_OK) return FM_ERROR; /* outputs are valid straight after initialisation */
    m->b.initialized = 1;
    return FM_OK;
}

/* ------------------------------------------------------------------ input and output guards
 *
 * The importer's inputs pass through guard_inputs() before the evaluator sees them
 * (docs/fmu.md, "Bad inputs"):
 *   - NaN keeps the evaluator's own replacement and warning (0; P: INFLPRES), except
 *     muRoad, which becomes 1 (no friction change) here;
 *   - +-Inf and finite values beyond the bounds below are saturated to the bound;
 *   - |x| < 1e-30 (subnormal and tiny values) is 0, silently: 1/x would overflow;
 *   - the bounds are the file's ranges widened to a guard band, or physical bounds
 *     where the file has no range:
 *       Fz     <= 3 FZMAX                 (negative: lift-off, set to 0 by the evaluator)
 *       kappa  |.| <= max(10, 2 max(|KPUMIN|, |KPUMAX|))
 *       alpha, gamma  |.| <= 1.55 rad     (just below 90 deg: tan() stays finite)
 *       phit   |.| <= 100 1/m
 *       Vx     |.| <= 200 m/s
 *       P      <= 3 PRESMAX               (<= 0 or -Inf: INFLPRES, as for NaN)
 *       omega  |.| <= 2000 rad/s
 *       muRoad 1e-3 .. 10                (no friction at all is outside the model: 0/0)
 *       data variables of the extensions  |.| <= 1e12 (NaN: 0 by the evaluator)
 * Each replacement is logged as a warning through the FMI logger (rate-limited like the
 * evaluator's warnings).  guard_outputs() is the last line: a published output that is
 * still not finite is set to 0 with a logged warning (known case: Mz, Mzr at Fz = 0 with
 * turn slip and limits, useMode 112, where the Python evaluator gives NaN too);
 * the fuzz test of tests/test_fmu_guards.py drives 10^5 random vectors through it.
 */
#define MF_GUARD_ALPHA 1.55
#define MF_GUARD_PHIT 100.0
#define MF_GUARD_VX 200.0
#define MF_GUARD_OMEGA 2000.0
#define MF_GUARD_MU 10.0
#define MF_GUARD_MU_MIN 1e-3
#define MF_GUARD_TINY 1e-30
#define MF_GUARD_DATA 1e12

static void guard_log(FMModel *m, unsigned slot, const char *name, double x, double to, const char *why)
{
    char text[256];
    snprintf(text, sizeof text, "input '%s' = %.17g %s %.17g.", name, x, why, to);
    fm_base_warn(&m->b, &m->guard[slot < MF_GUARD_SLOTS ? slot : MF_GUARD_SLOTS - 1], text);
}

/* Saturate x (NaN passes through for the evaluator to replace) to [lo, hi]; |x| < 1e-30 is 0. */
static double guard_clip(FMModel *m, unsigned slot, const char *name, double x, double lo, double hi)
{
    if (fabs(x) < MF_GUARD_TINY) x = 0.0 * x; /* keeps the sign of zero; subnormals overflow 1/x */
    if (x < lo) {
        guard_log(m, slot, name, x, lo, "saturated to the bound");
        return lo;
    }
    if (x > hi) {
        guard_log(m, slot, name, x, hi, "saturated to the bound");
        return hi;
    }
    return x;
}

static void guard_inputs(FMModel *m, MFInputs *in)
{
    const MFParams *p = &m->params;
    double kmax = fmax(10.0, 2.0 * fmax(fabs(p->KPUMIN), fabs(p->KPUMAX)));
    double fzmax = 3.0 * p->FZMAX, pmax = 3.0 * p->PRESMAX;
    int k;
    if (!(fzmax > 0.0)) fzmax = 3.0 * p->FNOMIN;
    if (!(pmax > 0.0)) pmax = 3.0 * p->INFLPRES;
    in->Fz = guard_clip(m, 0, "Fz", in->Fz, -HUGE_VAL, fzmax); /* -Inf: lift-off (0) in the evaluator */
    if (isinf(in->Fz)) in->Fz = 0.0;
    in->kappa = guard_clip(m, 1, "kappa", in->kappa, -kmax, kmax);
    in->alpha = guard_clip(m, 2, "alpha", in->alpha, -MF_GUARD_ALPHA, MF_GUARD_ALPHA);
    in->gamma = guard_clip(m, 3, "gamma", in->gamma, -MF_GUARD_ALPHA, MF_GUARD_ALPHA);
    in->phit = guard_clip(m, 4, "phit", in->phit, -MF_GUARD_PHIT, MF_GUARD_PHIT);
    in->Vx = guard_clip(m, 5, "Vx", in->Vx, -MF_GUARD_VX, MF_GUARD_VX);
    if (isinf(in->P) && in->P < 0.0) in->P = 0.0; /* <= 0 means INFLPRES */
    in->P = guard_clip(m, 6, "P", in->P, -HUGE_VAL, pmax);
    in->omega = guard_clip(m, 7, "omega", in->omega, -MF_GUARD_OMEGA, MF_GUARD_OMEGA);
    if (isnan(in->muRoad)) {
        guard_log(m, 8, "muRoad", in->muRoad, 1.0, "replaced by");
        in->muRoad = 1.0;
    }
    in->muRoad = guard_clip(m, 8, "muRoad", in->muRoad, MF_GUARD_MU_MIN, MF_GUARD_MU);
#if MF_N_DATA > 0
    {
        static const char *const names[MF_N_DATA] = MF_DATA_NAMES;
        for (k = 0; k < MF_N_DATA; k++)
            in->data[k] = guard_clip(m, 9 + (unsigned)k, names[k], in->data[k], -MF_GUARD_DATA, MF_GUARD_DATA);
    }
#endif
    (void)k;
}

static void guard_outputs(FMModel *m)
{
    double *o = (double *)&m->outputs;
    unsigned i, vr, n = sizeof m->outputs / sizeof(double), bad = 0;
    for (i = 0; i < n; i++) bad |= !isfinite(o[i]);
    if (!bad) return; /* the usual case: no look-up of the names */
    for (vr = 0; vr < MF_N_VARS; vr++)
        if (MF_VARS[vr].kind == FM_K_OUTPUT) {
            double *y = fm_slot(&m->outputs, &MF_VARS[vr]);
            if (!isfinite(*y)) {
                char text[160];
                snprintf(text, sizeof text, "output '%s' = %g is not finite; set to 0.", MF_VAR_NAMES[vr], *y);
                fm_base_warn(&m->b, &m->guard[MF_GUARD_SLOTS - 1], text);
                *y = 0.0;
            }
        }
    for (i = 0; i < n; i++)
        if (!isfinite(o[i])) o[i] = 0.0; /* members that are not FMU outputs (omega, Cx, Cy, Cz) */
}

/* Evaluate if the inputs, parameters or mode changed.  useMode and FITTYP are checked when they are set, in every
 * state (fm_set_mode, fm_set_parameter_ok), and their start values are checked at export, so the evaluation does
 * not check them again.  The evaluator's warnings take one path, the rate limit of fm_base_warn_kinds. */
static int update(FMModel *m)
{
    MFInputs in;
    if (!m->dirty) return FM_OK;
    m->b.evals++;
    in = m->inputs;
    guard_inputs(m, &in);
    fm_base_warn_kinds(&m->b, &m->params, mf_evaluate_unchecked(&m->params, m->b.use_mode, &in, MF_WANT_ALL,
                                                                 &m->outputs));
    guard_outputs(m);
    m->dirty = 0;
    return FM_OK;
}

static int fm_get_real(FMModel *m, unsigned vr, double *value)
{
    const FMVarInfo *v = fm_var(&TABLE, vr);
    if (v && v->kind == FM_K_OUTPUT) { /* the hot call first: an output, evaluated only when dirty */
        if (m->dirty && update(m) != FM_OK) return FM_ERROR;
        *value = *fm_slot(&m->outputs, v);
        return FM_OK;
    }
    if (v && fm_get_known(v, m->b.time, &m->inputs, &m->params, value)) return FM_OK;
    return fm_not_a(m->b.log, m->b.host, vr, "Real");
}

static int fm_set_real(FMModel *m, unsigned vr, double value)
{
    const FMVarInfo *v = fm_var(&TABLE, vr);
    if (!v) return fm_not_a(m->b.log, m->b.host, vr, "Real");
    switch (v->kind) {
    case FM_K_INPUT:
        *fm_slot(&m->inputs, v) = value;
        m->dirty = 1;
        return FM_OK;
    case FM_K_PARAM:
        if (fm_set_parameter_ok(m->b.log, m->b.host, &TABLE, &m->params, vr, value, m->b.initialized) != FM_OK)
            return FM_ERROR;
        *fm_slot(&m->params, v) = value;
        m->dirty = 1;
        return FM_OK;
    case FM_K_OUTPUT:
    case FM_K_TIME:
        logf_(m, FM_ERROR, "logStatusError", "%s cannot be set (causality %s)", MF_VAR_NAMES[vr],
              v->kind == FM_K_OUTPUT ? "output" : "independent");
        return FM_ERROR;
    default: return fm_not_a(m->b.log, m->b.host, vr, "Real");
    }
}

static int fm_get_int(FMModel *m, unsigned vr, int *value)
{
    return fm_get_mode(m->b.log, m->b.host, vr, MF_VR_USEMODE, m->b.use_mode, value);
}

static int fm_set_int(FMModel *m, unsigned vr, int value)
{
    if (fm_set_mode(m->b.log, m->b.host, vr, MF_VR_USEMODE, value, &m->b.use_mode) != FM_OK) return FM_ERROR;
    m->dirty = 1;
    return FM_OK;
}

/* ------------------------------------------------------------------ no continuous states */

static int fm_get_states(FMModel *m, double *x) { (void)m, (void)x; return FM_OK; }
static int fm_set_states(FMModel *m, const double *x) { (void)m, (void)x; return FM_OK; }
static int fm_get_derivatives(FMModel *m, double *dx) { (void)m, (void)dx; return FM_OK; }
static void fm_get_nominals(double *xn) { (void)xn; }

/* Co-Simulation: the inputs are held over the step; the outputs at its end are those of the inputs. */
static int fm_do_step(FMModel *m, double t, double h)
{
    m->b.time = t + h;
    return update(m);
}

#endif /* MF_FMU_UNITY */
