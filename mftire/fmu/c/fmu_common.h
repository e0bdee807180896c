/*
 * fmu_common.h -- what both models behind fmu_model.h (mf_model.c, mt_model.c) do alike: the value-reference
 * table and its accessors, log through the wrapper's logger, rate-limit repeated warnings, refuse
 * non-physical parameters and modes, check everything at the end of the initialisation.  Static functions of
 * the FMU's one translation unit (fmu.c).
 */
#ifndef FMU_COMMON_H
#define FMU_COMMON_H

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"
#include "mf_eval.h"

/* ------------------------------------------------------------------ the value-reference table
 *
 * One table type for every model: each model's generated header (mf_model_gen.h, mt_model_gen.h, written by
 * mftire.fmu.variables.value_reference_table) fills <P>_VARS[<P>_N_VARS] and <P>_VAR_NAMES, and the model
 * passes them to the accessors below as one FMVarTable. */
enum { FM_K_TIME = 0, FM_K_INPUT, FM_K_OUTPUT, FM_K_MODE, FM_K_PARAM, FM_K_STATE, FM_K_DER };

typedef struct {
    unsigned char kind;    /* FM_K_* */
    unsigned char fixed;   /* parameter with variability "fixed" */
    unsigned char want;    /* outputs: the channel groups (MF_WANT_*) they need */
    unsigned short offset; /* byte offset in the model's inputs / outputs / MFParams; state index */
} FMVarInfo;

typedef struct {
    const FMVarInfo *vars;
    const char *const *names;
    unsigned n;
} FMVarTable;

/* The entry of value reference vr (NULL where vr is no variable). */
FM_FN const FMVarInfo *fm_var(const FMVarTable *t, unsigned vr) { return vr < t->n ? &t->vars[vr] : NULL; }

/* The double of entry v in the struct at base (inputs, outputs or MFParams, as its kind says; written only
 * where base is the model's own). */
FM_FN double *fm_slot(const void *base, const FMVarInfo *v) { return (double *)((char *)base + v->offset); }

/* An output or a state derivative. */
FM_FN int fm_var_is_unknown(const FMVarTable *t, unsigned vr)
{
    const FMVarInfo *v = fm_var(t, vr);
    return v && (v->kind == FM_K_OUTPUT || v->kind == FM_K_DER);
}

/* What every unknown depends on: the inputs, then the states (fm_dependencies of fmu_model.h). */
FM_FN unsigned fm_var_dependencies(const FMVarTable *t, unsigned *vrs, unsigned room)
{
    unsigned vr, n = 0, pass;
    for (pass = 0; pass < 2; pass++)
        for (vr = 0; vr < t->n; vr++)
            if (t->vars[vr].kind == (pass ? FM_K_STATE : FM_K_INPUT)) {
                if (vrs && n < room) vrs[n] = vr;
                n++;
            }
    return n;
}

/* The value of a time, input or parameter variable, read alike by every model: 1 (*value set), else 0 (an
 * output, a state, ...: the model's own). */
FM_FN int fm_get_known(const FMVarInfo *v, double time, const void *inputs, const MFParams *p, double *value)
{
    switch (v->kind) {
    case FM_K_TIME: *value = time; return 1;
    case FM_K_INPUT: *value = *fm_slot(inputs, v); return 1;
    case FM_K_PARAM: *value = *fm_slot(p, v); return 1;
    default: return 0;
    }
}

/* Format and log through the wrapper's logger (log may be NULL). */
FM_FN void fm_logf(fm_log_fn log, void *host, int status, const char *category, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    if (!log) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    log(host, status, category, buf);
}

/* A warning the rate limit of fmu_model.h lets through, logged at time `time` with the number `skipped` of those
 * not logged since the last message. */
FM_FN void fm_log_warning(fm_log_fn log, void *host, double time, unsigned long skipped, const char *message)
{
    if (skipped)
        fm_logf(log, host, FM_WARNING, "logStatusWarning", "t=%.17g: %s (%lu more since the last message, not "
                "logged: one message per kind per %lu evaluations)", time, message, skipped, FM_WARN_EVERY);
    else
        fm_logf(log, host, FM_WARNING, "logStatusWarning", "t=%.17g: %s", time, message);
}

/* A warning through the rate limit: logged when its slot is due at evaluation `evals`. */
FM_FN void fm_warn(fm_log_fn log, void *host, FMWarnSlot *slot, unsigned long evals, double time, const char *message)
{
    unsigned long skipped;
    if (fm_warn_due(slot, evals, &skipped)) fm_log_warning(log, host, time, skipped, message);
}

/* Whether the model refuses the value of the parameter at `slot` in p (writing why into msg): any non-finite
 * value, the bounds of mftire.mf.spec.PARAMETER_BOUNDS, a FITTYP that names no model family the evaluator
 * handles -- as the export refuses them in the file. */
FM_FN int fm_check_parameter(const MFParams *p, const double *slot, double value, char *msg, unsigned long n)
{
    static const MFParamBound bounds[] = MF_SPEC_PARAMETER_BOUNDS;
    unsigned k;
    int index = (int)(slot - (const double *)p);
    if (!isfinite(value)) {
        snprintf(msg, n, "%g: a parameter must be finite", value);
        return 1;
    }
    for (k = 0; k < sizeof bounds / sizeof bounds[0]; k++)
        if (bounds[k].index == index && (bounds[k].strict ? !(value > bounds[k].bound) : !(value >= bounds[k].bound))) {
            snprintf(msg, n, "%s = %g must be %s %g", bounds[k].name, value, bounds[k].strict ? ">" : ">=",
                     bounds[k].bound);
            return 1;
        }
    if (slot == &p->FITTYP) {
        MFParams trial = *p;
        trial.FITTYP = value;
        return mf_check_fittyp(&trial, msg, n) != MF_OK;
    }
    return 0;
}

/* ------------------------------------------------------------------ what every model's FMI calls do alike
 *
 * A model instance (struct FMModel of the model file) starts with an FMBase (its first member, b): what every
 * model keeps alike.  logf_(m, ...) logs through its logger.  The helpers below take the logger and the
 * model's parameters explicitly. */
typedef struct {
    fm_log_fn log;
    void *host;                  /* the wrapper's instance */
    double time;
    int use_mode;
    int initialized;             /* after ExitInitializationMode */
    unsigned long evals;         /* evaluations so far (the clock of the warning rate limit) */
    FMWarnSlot warn[MF_W_COUNT]; /* the evaluator's warnings, per kind */
} FMBase;

#define FM_BASE(m) ((FMBase *)(m))
#define logf_(m, status, category, ...) fm_logf((m)->b.log, (m)->b.host, status, category, __VA_ARGS__)

/* The model interface's life cycle and clock, alike for every model (fmu_model.h; fm_reset is the model's). */
FM_FN void fm_init(FMModel *m, fm_log_fn log, void *host)
{
    memset(m, 0, fm_size());
    FM_BASE(m)->log = log;
    FM_BASE(m)->host = host;
    fm_reset(m);
}

FM_FN void fm_set_time(FMModel *m, double t) { FM_BASE(m)->time = t; }
FM_FN double fm_time(const FMModel *m) { return ((const FMBase *)m)->time; }

/* What every model's fm_reset does alike: time 0, the start value of useMode, not initialised, no evaluation
 * and no warning yet. */
FM_FN void fm_base_reset(FMBase *b, int use_mode)
{
    b->time = 0.0;
    b->use_mode = use_mode;
    b->initialized = 0;
    b->evals = 0;
    memset(b->warn, 0, sizeof b->warn);
}

/* A warning through the rate limit at the model's clock (slot: its kind, or a guard of the model). */
FM_FN void fm_base_warn(FMBase *b, FMWarnSlot *slot, const char *message)
{
    fm_warn(b->log, b->host, slot, b->evals, b->time, message);
}

/* The evaluator's warnings `kinds` (bit 1UL << kind of each MF_W_* kind, as mf_evaluate_unchecked returns them)
 * through the rate limit, in the order of the kinds: the text of a kind (mf_warning_text of p) is written only
 * when it is logged, not at each evaluation. */
FM_FN void fm_base_warn_kinds(FMBase *b, const MFParams *p, unsigned long kinds)
{
    char text[200];
    unsigned long skipped;
    int k;
    for (k = 0; kinds != 0 && k < MF_W_COUNT; k++, kinds >>= 1) /* the usual case: no warning, no loop */
        if ((kinds & 1UL) && fm_warn_due(&b->warn[k], b->evals, &skipped)) {
            mf_warning_text(p, k, text, sizeof text);
            fm_log_warning(b->log, b->host, b->time, skipped, text);
        }
}

/* Whether the parameter `name` at `slot` of p may take `value` now: a fixed parameter is not set after the
 * initialisation (fixed_now), and fm_check_parameter refuses non-physical values.  FM_OK, else the refusal is
 * logged and FM_ERROR returned (the parameter keeps its value). */
FM_FN int fm_parameter_ok(fm_log_fn log, void *host, const MFParams *p, const double *slot, double value,
                          int fixed_now, const char *name)
{
    char msg[256];
    if (fixed_now) {
        fm_logf(log, host, FM_ERROR, "logStatusError", "%s is a fixed parameter: it can only be set before "
                "initialisation", name);
        return FM_ERROR;
    }
    if (fm_check_parameter(p, slot, value, msg, sizeof msg)) {
        fm_logf(log, host, FM_ERROR, "logStatusError", "%s: %s", name, msg);
        return FM_ERROR;
    }
    return FM_OK;
}

/* Whether the parameter of value reference vr (entry v of table t) may be set to `value` now (fm_parameter_ok;
 * `initialized`: after ExitInitializationMode). */
FM_FN int fm_set_parameter_ok(fm_log_fn log, void *host, const FMVarTable *t, const MFParams *p, unsigned vr,
                              double value, int initialized)
{
    const FMVarInfo *v = &t->vars[vr];
    return fm_parameter_ok(log, host, p, fm_slot(p, v), value, v->fixed && initialized, t->names[vr]);
}

/* The checks of ExitInitializationMode, alike for every model: the FITTYP and the mode, then each parameter of
 * the table (fm_parameter_ok: the start values and those set before).  FM_OK, else the first refusal is logged
 * and FM_ERROR returned. */
FM_FN int fm_check_initialization(fm_log_fn log, void *host, const MFParams *p, int use_mode, const FMVarTable *t)
{
    char msg[256];
    unsigned vr;
    if (mf_check_fittyp(p, msg, sizeof msg) != MF_OK || mf_check_mode(use_mode, msg, sizeof msg) != MF_OK) {
        fm_logf(log, host, FM_ERROR, "logStatusError", "%s", msg);
        return FM_ERROR;
    }
    for (vr = 0; vr < t->n; vr++)
        if (t->vars[vr].kind == FM_K_PARAM && fm_set_parameter_ok(log, host, t, p, vr, *fm_slot(p, &t->vars[vr]), 0)
            != FM_OK)
            return FM_ERROR;
    return FM_OK;
}

/* The error for a value reference vr that is not a variable of type `type` ("Real", "Integer") of the model,
 * logged.  Returns FM_ERROR. */
FM_FN int fm_not_a(fm_log_fn log, void *host, unsigned vr, const char *type)
{
    fm_logf(log, host, FM_ERROR, "logStatusError", "value reference %u is not a%s %s variable", vr,
            type[0] == 'I' ? "n" : "", type);
    return FM_ERROR;
}

/* useMode, the one Integer variable of every model (value reference vr_mode): read into *value. */
FM_FN int fm_get_mode(fm_log_fn log, void *host, unsigned vr, unsigned vr_mode, int mode, int *value)
{
    if (vr != vr_mode) return fm_not_a(log, host, vr, "Integer");
    *value = mode;
    return FM_OK;
}

/* useMode set to value, where the evaluator takes it: FM_OK (*mode set), else the refusal is logged and
 * FM_ERROR returned. */
FM_FN int fm_set_mode(fm_log_fn log, void *host, unsigned vr, unsigned vr_mode, int value, int *mode)
{
    char msg[256];
    if (vr != vr_mode) return fm_not_a(log, host, vr, "Integer");
    if (mf_check_mode(value, msg, sizeof msg) != MF_OK) {
        fm_logf(log, host, FM_ERROR, "logStatusError", "%s", msg);
        return FM_ERROR;
    }
    *mode = value;
    return FM_OK;
}

#endif /* FMU_COMMON_H */
