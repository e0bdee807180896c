/*
 * mf_model.c -- instance state shared by the FMI 2.0 and 3.0 wrappers.
 *
 * All variables are addressed through the value-reference table generated into
 * mf_model_gen.h from the Python variable table (mftire/fmu/variables.py).
 * Outputs are evaluated lazily: setting an input or a parameter marks the
 * instance dirty, reading an output evaluates once.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "mf_model.h"
#include "mf_model_gen.h"

const char *mf_model_var_name(unsigned vr) { return vr < MF_N_VARS ? MF_VAR_NAMES[vr] : "?"; }
unsigned mf_model_n_vars(void) { return MF_N_VARS; }
const char *mf_model_guid(void) { return MF_GUID; }
int mf_model_is_output(unsigned vr) { return vr < MF_N_VARS && MF_VARS[vr].kind == MF_K_OUTPUT; }

unsigned mf_model_input_vrs(unsigned *vrs)
{
    unsigned vr, n = 0;
    for (vr = 0; vr < MF_N_VARS; vr++)
        if (MF_VARS[vr].kind == MF_K_INPUT) {
            if (vrs && n < 64) vrs[n] = vr;
            n++;
        }
    return n;
}

void mf_model_logf(MFModel *m, int status, const char *category, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    if (!m->log) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    m->log(m, status, category, buf);
}

void mf_model_reset(MFModel *m)
{
    m->params = MF_PARAM_START;
    m->inputs = MF_INPUT_START;
    memset(&m->outputs, 0, sizeof m->outputs);
    m->use_mode = MF_USEMODE_START;
    m->time = 0.0;
    m->dirty = 1;
    m->initialized = 0;
    memset(m->warn_count, 0, sizeof m->warn_count);
    memset(m->guard_count, 0, sizeof m->guard_count);
}

void mf_model_init(MFModel *m, mf_log_fn log, void *host)
{
    memset(m, 0, sizeof *m);
    m->log = log;
    m->host = host;
    mf_model_reset(m);
}

int mf_model_validate(MFModel *m)
{
    char msg[256];
    if (mf_check_fittyp(&m->params, msg, sizeof msg) != MF_OK ||
        mf_check_mode(m->use_mode, msg, sizeof msg) != MF_OK) {
        mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "%s", msg);
        return MF_STATUS_ERROR;
    }
    return MF_STATUS_OK;
}

static void on_warning(void *ctx, int kind, const char *message)
{
    MFModel *m = (MFModel *)ctx;
    unsigned n = ++m->warn_count[kind];
    if (m->debug_logging || n <= MF_WARN_REPEAT)
        mf_model_logf(m, MF_STATUS_WARNING, "logStatusWarning", "t=%.17g: %s", m->time, message);
    if (!m->debug_logging && n == MF_WARN_REPEAT)
        mf_model_logf(m, MF_STATUS_WARNING, "logStatusWarning",
                      "this warning has been logged %d times and is now muted (enable debug logging to see all)",
                      MF_WARN_REPEAT);
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
#define MF_N_PUBLISHED 19 /* MFOutputs members the FMU publishes (Fx .. sigmay) */

static void guard_log(MFModel *m, unsigned slot, const char *name, double x, double to, const char *why)
{
    unsigned n = slot < MF_GUARD_SLOTS ? ++m->guard_count[slot] : MF_WARN_REPEAT + 1;
    if (m->debug_logging || n <= MF_WARN_REPEAT)
        mf_model_logf(m, MF_STATUS_WARNING, "logStatusWarning", "t=%.17g: input '%s' = %.17g %s %.17g.", m->time,
                      name, x, why, to);
    if (!m->debug_logging && n == MF_WARN_REPEAT)
        mf_model_logf(m, MF_STATUS_WARNING, "logStatusWarning",
                      "this warning has been logged %d times and is now muted (enable debug logging to see all)",
                      MF_WARN_REPEAT);
}

/* Saturate x (NaN passes through for the evaluator to replace) to [lo, hi]; |x| < 1e-30 is 0. */
static double guard_clip(MFModel *m, unsigned slot, const char *name, double x, double lo, double hi)
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

static void guard_inputs(MFModel *m, MFInputs *in)
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

static void guard_outputs(MFModel *m)
{
    static const char *const names[] = {"Fx", "Fy", "Fz", "Mx", "My", "Mz", "Re", "Rl", "rho", "a2", "b2", "t",
                                        "Mzr", "mux", "muy", "Kxk", "Kya", "sigmax", "sigmay", "omega", "Cx", "Cy",
                                        "Cz"};
    double *o = (double *)&m->outputs;
    unsigned i, n = sizeof m->outputs / sizeof(double);
    for (i = 0; i < n; i++)
        if (!isfinite(o[i]) && i >= MF_N_PUBLISHED) {
            o[i] = 0.0; /* internal (omega, Cx, Cy, Cz): not an FMU output */
        } else if (!isfinite(o[i])) {
            unsigned c = ++m->guard_count[MF_GUARD_SLOTS - 1];
            if (m->debug_logging || c <= MF_WARN_REPEAT)
                mf_model_logf(m, MF_STATUS_WARNING, "logStatusWarning", "t=%.17g: output '%s' = %g is not finite; "
                              "set to 0.", m->time, i < sizeof names / sizeof names[0] ? names[i] : "?", o[i]);
            o[i] = 0.0;
        }
}

int mf_model_update(MFModel *m)
{
    char msg[256];
    int rc;
    MFInputs in;
    if (!m->dirty) return MF_STATUS_OK;
    in = m->inputs;
    guard_inputs(m, &in);
    rc = mf_evaluate(&m->params, m->use_mode, &in, &m->outputs, on_warning, m);
    if (rc == MF_OK) guard_outputs(m);
    if (rc != MF_OK) {
        if (rc == MF_BAD_MODE) mf_check_mode(m->use_mode, msg, sizeof msg);
        else mf_check_fittyp(&m->params, msg, sizeof msg);
        mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "%s", msg);
        return MF_STATUS_ERROR;
    }
    m->dirty = 0;
    return MF_STATUS_OK;
}

int mf_model_get_real(MFModel *m, unsigned vr, double *value)
{
    const MFVarInfo *v;
    if (vr >= MF_N_VARS) goto bad;
    v = &MF_VARS[vr];
    switch (v->kind) {
    case MF_K_TIME: *value = m->time; return MF_STATUS_OK;
    case MF_K_INPUT: *value = *(const double *)((const char *)&m->inputs + v->offset); return MF_STATUS_OK;
    case MF_K_PARAM: *value = *(const double *)((const char *)&m->params + v->offset); return MF_STATUS_OK;
    case MF_K_OUTPUT:
        if (mf_model_update(m) != MF_STATUS_OK) return MF_STATUS_ERROR;
        *value = *(const double *)((const char *)&m->outputs + v->offset);
        return MF_STATUS_OK;
    default: break;
    }
bad:
    mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "value reference %u is not a Real variable", vr);
    return MF_STATUS_ERROR;
}

int mf_model_set_real(MFModel *m, unsigned vr, double value)
{
    const MFVarInfo *v;
    if (vr >= MF_N_VARS) goto bad;
    v = &MF_VARS[vr];
    if (v->kind == MF_K_INPUT) {
        *(double *)((char *)&m->inputs + v->offset) = value;
        m->dirty = 1;
        return MF_STATUS_OK;
    }
    if (v->kind == MF_K_PARAM) {
        double *slot = (double *)((char *)&m->params + v->offset);
        if (v->fixed && m->initialized) {
            mf_model_logf(m, MF_STATUS_ERROR, "logStatusError",
                          "%s is a fixed parameter: it can only be set before initialisation", MF_VAR_NAMES[vr]);
            return MF_STATUS_ERROR;
        }
        if (slot == &m->params.FITTYP) {
            MFParams trial = m->params;
            char msg[256];
            trial.FITTYP = value;
            if (mf_check_fittyp(&trial, msg, sizeof msg) != MF_OK) {
                mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "%s", msg);
                return MF_STATUS_ERROR;
            }
        }
        *slot = value;
        m->dirty = 1;
        return MF_STATUS_OK;
    }
    if (v->kind == MF_K_OUTPUT || v->kind == MF_K_TIME) {
        mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "%s cannot be set (causality %s)", MF_VAR_NAMES[vr],
                      v->kind == MF_K_OUTPUT ? "output" : "independent");
        return MF_STATUS_ERROR;
    }
bad:
    mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "value reference %u is not a Real variable", vr);
    return MF_STATUS_ERROR;
}

int mf_model_get_int(MFModel *m, unsigned vr, int *value)
{
    if (vr == MF_VR_USEMODE) {
        *value = m->use_mode;
        return MF_STATUS_OK;
    }
    mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "value reference %u is not an Integer variable", vr);
    return MF_STATUS_ERROR;
}

int mf_model_set_int(MFModel *m, unsigned vr, int value)
{
    char msg[256];
    if (vr != MF_VR_USEMODE) {
        mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "value reference %u is not an Integer variable", vr);
        return MF_STATUS_ERROR;
    }
    if (mf_check_mode(value, msg, sizeof msg) != MF_OK) {
        mf_model_logf(m, MF_STATUS_ERROR, "logStatusError", "%s", msg);
        return MF_STATUS_ERROR;
    }
    m->use_mode = value;
    m->dirty = 1;
    return MF_STATUS_OK;
}
