/*
 * mt_model.c -- the transient tyre behind the FMI wrappers (fmu_model.h): two continuous states
 * u, v (the contact-point slip deflections) with their derivatives, on mf_transient.c.
 *
 * Model Exchange: fm_get_derivatives returns (du/dt, dv/dt) of mftire/transient.py.
 * Co-Simulation: fm_do_step holds the inputs over the communication step H and advances the
 * states with mt_advance (mf_transient.c: the integration is the model's, not the wrapper's).
 *
 * Outputs are computed lazily: the first read of an output after new inputs, states or a step
 * evaluates the Magic Formula at the transient slips for the channel groups (MF_WANT_* of mf_eval.h)
 * of every output read so far (MTVarInfo.want), and the zero-slip evaluation of the kinematics computes
 * the rolling offsets only below VXLOW and only for those groups.  Each output equals the full
 * evaluation (mt_outputs with MF_WANT_ALL) bit for bit; a group read for the first time is added
 * (one more evaluation then).  An input set to its present value (bit for bit) changes nothing.
 *
 * The value-reference table, start values and GUID come from mt_model_gen.h, generated
 * by mftire/fmu/transient_export.py from one variable table.
 */
#ifdef MF_FMU_UNITY /* a part of fmu.c (alone, for an importer that compiles every .c: nothing) */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_common.h"
#include "mf_transient.h"
#include "mt_model_gen.h"

/* The input guard of the transient model (mt_guard_inputs of mf_transient.c: non-finite inputs hold their last
 * good value, inputs beyond their physical bounds are saturated), where the model provides it. */
#if defined(MT_N_INPUTS)
#define MT_HAS_GUARD 1
#else
#define MT_HAS_GUARD 0
#endif

struct FMModel {
    MFParams params;
    MTInputs inputs;
#if MT_HAS_GUARD
    MTInputs held;                  /* last good inputs (mt_guard_inputs) */
    FMWarnSlot guard[MT_N_INPUTS];  /* the guard's warnings, per input */
    FMWarnSlot nonfinite;           /* outputs set to 0 by mt_outputs */
#endif
    double x[2];
    MTKin kin;
    MTOutputs out;
    int kin_ok, out_ok;
    unsigned out_have; /* channel groups of out (valid when out_ok) */
    unsigned out_want; /* channel groups of every output read so far */
    int use_mode;
    double time;
    int initialized;
    unsigned long evals; /* output and derivative evaluations so far (the clock of the warning rate limit) */
    FMWarnSlot warn[MF_W_COUNT];
    fm_log_fn log;
    void *host;
};

static const char *fm_guid(void) { return MT_GUID; }
static size_t fm_size(void) { return sizeof(FMModel); }
static unsigned fm_n_states(void) { return 2; }
static int fm_is_unknown(unsigned vr)
{
    return vr < MT_N_VARS && (MT_VARS[vr].kind == MT_K_OUTPUT || MT_VARS[vr].kind == MT_K_DER);
}
static void fm_set_time(FMModel *m, double t) { m->time = t; }
static double fm_time(const FMModel *m) { return m->time; }

static unsigned fm_dependencies(unsigned *vrs, unsigned room)
{
    unsigned vr, n = 0, pass;
    for (pass = 0; pass < 2; pass++)
        for (vr = 0; vr < MT_N_VARS; vr++)
            if (MT_VARS[vr].kind == (pass ? MT_K_STATE : MT_K_INPUT)) {
                if (vrs && n < room) vrs[n] = vr;
                n++;
            }
    return n;
}

static void on_warning(void *ctx, int kind, const char *message)
{
    FMModel *m = (FMModel *)ctx;
    if (kind == MF_W_LOW_SPEED || kind < 0 || kind >= MF_W_COUNT) return; /* the transient model replaces
                                                                               MFeval's low-speed mode */
    fm_warn(m->log, m->host, &m->warn[kind], m->evals, m->time, message);
}

static void fm_reset(FMModel *m)
{
    m->params = MT_PARAM_START;
    m->inputs = MT_INPUT_START;
#if MT_HAS_GUARD
    m->held = MT_INPUT_START;
    memset(m->guard, 0, sizeof m->guard);
    memset(&m->nonfinite, 0, sizeof m->nonfinite);
#endif
    m->x[0] = MT_STATE_START[0];
    m->x[1] = MT_STATE_START[1];
    m->use_mode = MT_USEMODE_START;
    m->time = 0.0;
    m->kin_ok = m->out_ok = 0;
    m->out_have = m->out_want = 0;
    m->initialized = 0;
    m->evals = 0;
    memset(m->warn, 0, sizeof m->warn);
}

static void fm_init(FMModel *m, fm_log_fn log, void *host)
{
    memset(m, 0, sizeof *m);
    m->log = log;
    m->host = host;
    fm_reset(m);
}

static int bad_code(FMModel *m, int rc)
{
    return fm_eval_error(m->log, m->host, &m->params, m->use_mode, rc);
}

/* The kinematics, with the rolling offsets of the output groups read so far. */
static int update_kin(FMModel *m)
{
    int rc;
    MTInputs in;
    if (m->kin_ok && !(m->out_want & MT_OFFSETS & ~m->kin.offsets)) return 0;
    in = m->inputs;
#if MT_HAS_GUARD
    {
        unsigned i, bad = mt_guard_inputs(&m->params, &in, &m->held); /* the model's guard, before the states */
        char text[160];
        for (i = 0; i < MT_N_INPUTS; i++)
            if (bad & (1u << i)) {
                snprintf(text, sizeof text, "input '%s' not finite or out of range: the last good value or the "
                         "bound is used", mt_input_name(i));
                fm_warn(m->log, m->host, &m->guard[i], m->evals, m->time, text);
            }
    }
#endif
    rc = mt_kinematics(&m->params, m->use_mode, &in, m->out_want, &m->kin, on_warning, m);
    if (rc != MF_OK) return bad_code(m, rc);
    m->kin_ok = 1;
    return 0;
}

/* The outputs of the channel groups `want` (and of all groups read before). */
static int update_out(FMModel *m, unsigned want)
{
    int rc;
    m->out_want |= want;
    if (m->out_ok && !(m->out_want & ~m->out_have)) return 0;
    m->evals++; /* the clock of the warning rate limit: output evaluations and derivative evaluations */
    if (update_kin(m)) return 1;
    rc = mt_outputs(&m->params, m->use_mode, &m->kin, m->x, m->out_want, &m->out, on_warning, m);
    if (rc != MF_OK) return bad_code(m, rc);
#if MT_HAS_GUARD
    if (m->out.nonfinite) {
        char text[96];
        snprintf(text, sizeof text, "%u output(s) not finite, set to 0", m->out.nonfinite);
        fm_warn(m->log, m->host, &m->nonfinite, m->evals, m->time, text);
    }
#endif
    m->out_have = m->out_want;
    m->out_ok = 1;
    return 0;
}

/* Store an input or parameter; the kinematics and outputs are out of date unless the value is the same. */
static void store(FMModel *m, double *dst, double value)
{
    if (memcmp(dst, &value, sizeof value) == 0) return; /* bit for bit the same: nothing changes */
    *dst = value;
    m->kin_ok = m->out_ok = 0;
}

/* The parameter at value reference vr (fm_param_fn of fmu_common.h; the bounds of mftire.mf.spec, VXLOW > 0,
 * TR_SAT >= 0 and TR_CS_STEP > 0 among them, are checked by fm_parameter_ok). */
static const double *param_at(const MFParams *p, unsigned vr, const char **name)
{
    if (MT_VARS[vr].kind != MT_K_PARAM) return NULL;
    *name = MT_VAR_NAMES[vr];
    return (const double *)((const char *)p + MT_VARS[vr].offset);
}

static int fm_exit_initialization(FMModel *m)
{
    if (fm_check_initialization(m->log, m->host, &m->params, m->use_mode, MT_N_VARS, param_at) != FM_OK)
        return FM_ERROR;
    if (update_out(m, 0)) return FM_ERROR;
    m->initialized = 1;
    return FM_OK;
}

static int fm_get_real(FMModel *m, unsigned vr, double *value)
{
    const MTVarInfo *v;
    double dx[2];
    if (vr >= MT_N_VARS) goto bad;
    v = &MT_VARS[vr];
    switch (v->kind) {
    case MT_K_TIME: *value = m->time; return FM_OK;
    case MT_K_INPUT: *value = *(const double *)((const char *)&m->inputs + v->offset); return FM_OK;
    case MT_K_PARAM: *value = *(const double *)((const char *)&m->params + v->offset); return FM_OK;
    case MT_K_STATE: *value = m->x[v->offset]; return FM_OK;
    case MT_K_DER:
        if (update_kin(m)) return FM_ERROR;
        mt_rates(&m->params, &m->kin, m->x, dx);
        *value = dx[v->offset];
        return FM_OK;
    case MT_K_OUTPUT:
        if (update_out(m, v->want)) return FM_ERROR;
        *value = *(const double *)((const char *)&m->out + v->offset);
        return FM_OK;
    default: break;
    }
bad:
    return fm_not_a(m->log, m->host, vr, "Real");
}

static int fm_set_real(FMModel *m, unsigned vr, double value)
{
    const MTVarInfo *v;
    if (vr >= MT_N_VARS) goto bad;
    v = &MT_VARS[vr];
    switch (v->kind) {
    case MT_K_INPUT:
        store(m, (double *)((char *)&m->inputs + v->offset), value);
        return FM_OK;
    case MT_K_PARAM:
        if (fm_parameter_ok(m->log, m->host, &m->params, (const double *)((const char *)&m->params + v->offset), value,
                            v->fixed && m->initialized, MT_VAR_NAMES[vr]) != FM_OK)
            return FM_ERROR;
        store(m, (double *)((char *)&m->params + v->offset), value);
        return FM_OK;
    case MT_K_STATE:
        if (m->initialized) {
            logf_(m, FM_ERROR, "logStatusError", "%s: set states with fmi2SetContinuousStates / "
                  "fmi3SetContinuousStates", MT_VAR_NAMES[vr]);
            return FM_ERROR;
        }
        m->x[v->offset] = value;
        m->out_ok = 0;
        return FM_OK;
    default:
        logf_(m, FM_ERROR, "logStatusError", "%s cannot be set", MT_VAR_NAMES[vr]);
        return FM_ERROR;
    }
bad:
    return fm_not_a(m->log, m->host, vr, "Real");
}

static int fm_get_int(FMModel *m, unsigned vr, int *value)
{
    return fm_get_mode(m->log, m->host, vr, MT_VR_USEMODE, m->use_mode, value);
}

static int fm_set_int(FMModel *m, unsigned vr, int value)
{
    if (fm_set_mode(m->log, m->host, vr, MT_VR_USEMODE, value, &m->use_mode) != FM_OK) return FM_ERROR;
    m->kin_ok = m->out_ok = 0;
    return FM_OK;
}

/* ------------------------------------------------------------------ Model Exchange */

static int fm_set_states(FMModel *m, const double *x)
{
    m->x[0] = x[0];
    m->x[1] = x[1];
    m->out_ok = 0;
    return FM_OK;
}

static int fm_get_states(FMModel *m, double *x)
{
    x[0] = m->x[0];
    x[1] = m->x[1];
    return FM_OK;
}

static int fm_get_derivatives(FMModel *m, double *dx)
{
    m->evals++;
    if (update_kin(m)) return FM_ERROR;
    mt_rates(&m->params, &m->kin, m->x, dx);
    return FM_OK;
}

static void fm_get_nominals(double *xn) { xn[0] = xn[1] = 1e-3; /* deflections of the order of a millimetre */ }

/* ------------------------------------------------------------------ Co-Simulation */

static int fm_do_step(FMModel *m, double t, double h)
{
    if (update_kin(m)) return FM_ERROR; /* inputs are held over the step */
    mt_advance(&m->params, &m->kin, m->x, h);
    m->time = t + h;
    m->out_ok = 0; /* the outputs at the new state are computed when read */
    return FM_OK;
}

#endif /* MF_FMU_UNITY */
