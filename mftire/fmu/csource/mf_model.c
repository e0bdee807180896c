/*
 * mf_model.c -- instance state shared by the FMI 2.0 and 3.0 wrappers.
 *
 * All variables are addressed through the value-reference table generated into
 * mf_model_gen.h from the Python variable table (mftire/fmu/variables.py).
 * Outputs are evaluated lazily: setting an input or a parameter marks the
 * instance dirty, reading an output evaluates once.
 */
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

int mf_model_update(MFModel *m)
{
    char msg[256];
    int rc;
    if (!m->dirty) return MF_STATUS_OK;
    rc = mf_evaluate(&m->params, m->use_mode, &m->inputs, &m->outputs, on_warning, m);
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
