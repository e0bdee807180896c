/*
 * fmi2_transient.c -- FMI 2.0 Model Exchange and Co-Simulation wrapper of the
 * transient tyre (mf_transient.c): two continuous states u, v with derivatives.
 *
 * Model Exchange: fmi2GetDerivatives returns (du/dt, dv/dt) of mftire/transient.py.
 * Co-Simulation: fmi2DoStep holds the inputs over the communication step H and solves
 * the linear lag exactly in one step while the deflection limiter stays inactive; else
 * it takes n = ceil(H / TR_CS_STEP) equal exponential-Euler sub-steps (TR_CS_STEP:
 * tunable parameter, default 1e-4 s).  See mt_advance in mf_transient.c.
 *
 * Outputs are computed lazily: the first fmi2GetReal of an output after new inputs, states or a step
 * evaluates the Magic Formula at the transient slips for the channel groups (MF_WANT_* of mf_eval.h)
 * of every output read so far (MTVarInfo.want), and the zero-slip evaluation of the kinematics computes
 * the rolling offsets only below VXLOW and only for those groups.  Each output equals the full
 * evaluation (mt_outputs with MF_WANT_ALL) bit for bit; a group read for the first time is added
 * (one more evaluation then).  An input set to its present value (bit for bit) changes nothing.
 *
 * The value-reference table, start values and GUID come from mt_model_gen.h, generated
 * by mftire/fmu/transient_export.py from one variable table.  The functions that do not
 * depend on the model are in fmi2_common.c, shared with the steady-state tyre.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_common.h"
#include "mf_transient.h"
#include "mt_model_gen.h"

#define WARN_REPEAT 10

typedef struct {
    FMI2Base base; /* first: fmi2_common.c sees the instance as an FMI2Base */
    MFParams params;
    MTInputs inputs;
    MTInputs held; /* last good inputs (mt_guard_inputs) */
    unsigned guard_count[MT_N_INPUTS];
    unsigned nonfinite_count;
    double x[2];
    MTKin kin;
    MTOutputs out;
    int kin_ok, out_ok;
    unsigned out_have; /* channel groups of out (valid when out_ok) */
    unsigned out_want; /* channel groups of every output read so far */
    int use_mode;
    double time;
    int debug_logging;
    unsigned warn_count[MF_W_COUNT];
} Instance;

#define INS ((Instance *)c)

static void on_warning(void *ctx, int kind, const char *message)
{
    Instance *ins = (Instance *)ctx;
    unsigned n;
    if (kind == MF_W_LOW_SPEED) return; /* the transient model replaces MFeval's low-speed mode */
    n = ++ins->warn_count[kind];
    if (ins->debug_logging || n <= WARN_REPEAT)
        fmi2_logf(&ins->base, fmi2Warning, "logStatusWarning", "t=%.17g: %s", ins->time, message);
    if (!ins->debug_logging && n == WARN_REPEAT)
        fmi2_logf(&ins->base, fmi2Warning, "logStatusWarning", "this warning is now muted (enable debug logging to see all)");
}

static void reset(Instance *ins)
{
    ins->params = MT_PARAM_START;
    ins->inputs = MT_INPUT_START;
    ins->held = MT_INPUT_START;
    memset(ins->guard_count, 0, sizeof ins->guard_count);
    ins->nonfinite_count = 0;
    ins->x[0] = MT_STATE_START[0];
    ins->x[1] = MT_STATE_START[1];
    ins->use_mode = MT_USEMODE_START;
    ins->time = 0.0;
    ins->kin_ok = ins->out_ok = 0;
    ins->out_have = ins->out_want = 0;
    memset(ins->warn_count, 0, sizeof ins->warn_count);
}

static int bad_code(Instance *ins, int rc)
{
    char msg[256];
    if (rc == MF_BAD_MODE) mf_check_mode(ins->use_mode, msg, sizeof msg);
    else mf_check_fittyp(&ins->params, msg, sizeof msg);
    fmi2_logf(&ins->base, fmi2Error, "logStatusError", "%s", msg);
    return 1;
}

/* The kinematics, with the rolling offsets of the output groups read so far. */
static int update_kin(Instance *ins)
{
    int rc;
    unsigned bad, i;
    MTInputs in;
    if (ins->kin_ok && !(ins->out_want & MT_OFFSETS & ~ins->kin.offsets)) return 0;
    in = ins->inputs;
    bad = mt_guard_inputs(&ins->params, &in, &ins->held); /* non-finite: last good value; beyond bounds: bound */
    for (i = 0; i < MT_N_INPUTS; i++)
        if (bad & (1u << i)) {
            unsigned n = ++ins->guard_count[i];
            if (ins->debug_logging || n <= WARN_REPEAT)
                fmi2_logf(&ins->base, fmi2Warning, "logStatusWarning",
                          "t=%.17g: input '%s' not finite or out of range: the last good value or the bound is used",
                          ins->time, mt_input_name(i));
        }
    rc = mt_kinematics(&ins->params, ins->use_mode, &in, ins->out_want, &ins->kin, on_warning, ins);
    if (rc != MF_OK) return bad_code(ins, rc);
    ins->kin_ok = 1;
    return 0;
}

/* The outputs of the channel groups `want` (and of all groups read before). */
static int update_out(Instance *ins, unsigned want)
{
    int rc;
    ins->out_want |= want;
    if (ins->out_ok && !(ins->out_want & ~ins->out_have)) return 0;
    if (update_kin(ins)) return 1;
    rc = mt_outputs(&ins->params, ins->use_mode, &ins->kin, ins->x, ins->out_want, &ins->out, on_warning, ins);
    if (rc != MF_OK) return bad_code(ins, rc);
    if (ins->out.nonfinite && (ins->debug_logging || ++ins->nonfinite_count <= WARN_REPEAT))
        fmi2_logf(&ins->base, fmi2Warning, "logStatusWarning", "t=%.17g: %u output(s) not finite, set to 0", ins->time,
                  ins->out.nonfinite);
    ins->out_have = ins->out_want;
    ins->out_ok = 1;
    return 0;
}

/* Store an input or parameter; the kinematics and outputs are out of date unless the value is the same. */
static void store(Instance *ins, double *dst, double value)
{
    if (memcmp(dst, &value, sizeof value) == 0) return; /* bit for bit the same: nothing changes */
    *dst = value;
    ins->kin_ok = ins->out_ok = 0;
}

static fmi2Status get_real(Instance *ins, unsigned vr, double *value)
{
    const MTVarInfo *v;
    double dx[2];
    if (vr >= MT_N_VARS) goto bad;
    v = &MT_VARS[vr];
    switch (v->kind) {
    case MT_K_TIME: *value = ins->time; return fmi2OK;
    case MT_K_INPUT: *value = *(const double *)((const char *)&ins->inputs + v->offset); return fmi2OK;
    case MT_K_PARAM: *value = *(const double *)((const char *)&ins->params + v->offset); return fmi2OK;
    case MT_K_STATE: *value = ins->x[v->offset]; return fmi2OK;
    case MT_K_DER:
        if (update_kin(ins)) return fmi2Error;
        mt_rates(&ins->params, &ins->kin, ins->x, dx);
        *value = dx[v->offset];
        return fmi2OK;
    case MT_K_OUTPUT:
        if (update_out(ins, v->want)) return fmi2Error;
        *value = *(const double *)((const char *)&ins->out + v->offset);
        return fmi2OK;
    default: break;
    }
bad:
    fmi2_logf(&ins->base, fmi2Error, "logStatusError", "value reference %u is not a Real variable", vr);
    return fmi2Error;
}

static fmi2Status set_real(Instance *ins, unsigned vr, double value)
{
    const MTVarInfo *v;
    if (vr >= MT_N_VARS) goto bad;
    v = &MT_VARS[vr];
    switch (v->kind) {
    case MT_K_INPUT:
        store(ins, (double *)((char *)&ins->inputs + v->offset), value);
        return fmi2OK;
    case MT_K_PARAM:
        if (v->fixed && ins->base.state != FMI2_INSTANTIATED && ins->base.state != FMI2_INIT) {
            fmi2_logf(&ins->base, fmi2Error, "logStatusError", "%s is a fixed parameter", MT_VAR_NAMES[vr]);
            return fmi2Error;
        }
        store(ins, (double *)((char *)&ins->params + v->offset), value);
        return fmi2OK;
    case MT_K_STATE:
        if (ins->base.state == FMI2_RUNNING) {
            fmi2_logf(&ins->base, fmi2Error, "logStatusError", "%s: set states with fmi2SetContinuousStates", MT_VAR_NAMES[vr]);
            return fmi2Error;
        }
        ins->x[v->offset] = value;
        ins->out_ok = 0;
        return fmi2OK;
    default:
        fmi2_logf(&ins->base, fmi2Error, "logStatusError", "%s cannot be set", MT_VAR_NAMES[vr]);
        return fmi2Error;
    }
bad:
    fmi2_logf(&ins->base, fmi2Error, "logStatusError", "value reference %u is not a Real variable", vr);
    return fmi2Error;
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Instance *ins;
    (void)fmuResourceLocation;
    (void)visible;
    ins = (Instance *)fmi2_base_new(sizeof(Instance), instanceName, fmuType, fmuGUID, MT_GUID, functions);
    if (!ins) return NULL;
    ins->base.debug_logging = &ins->debug_logging;
    ins->base.time = &ins->time;
    ins->debug_logging = loggingOn ? 1 : 0;
    reset(ins);
    return ins;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    char msg[256];
    if (!c) return fmi2Error;
    if (mf_check_fittyp(&INS->params, msg, sizeof msg) != MF_OK || mf_check_mode(INS->use_mode, msg, sizeof msg) != MF_OK) {
        fmi2_logf(&INS->base, fmi2Error, "logStatusError", "%s", msg);
        INS->base.state = FMI2_ERROR;
        return fmi2Error;
    }
    if (INS->params.TR_CS_STEP <= 0.0 || INS->params.VXLOW <= 0.0) {
        fmi2_logf(&INS->base, fmi2Error, "logStatusError", "TR_CS_STEP and VXLOW must be positive");
        INS->base.state = FMI2_ERROR;
        return fmi2Error;
    }
    if (update_out(INS, 0)) {
        INS->base.state = FMI2_ERROR;
        return fmi2Error;
    }
    INS->base.state = FMI2_RUNNING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c)
{
    if (!c) return fmi2Error;
    reset(INS);
    INS->base.state = FMI2_INSTANTIATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (get_real(INS, vr[i], &value[i]) != fmi2OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (set_real(INS, vr[i], value[i]) != fmi2OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++) {
        if (vr[i] != MT_VR_USEMODE) {
            fmi2_logf(&INS->base, fmi2Error, "logStatusError", "value reference %u is not an Integer variable", vr[i]);
            return fmi2Error;
        }
        value[i] = INS->use_mode;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer value[])
{
    size_t i;
    char msg[256];
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++) {
        if (vr[i] != MT_VR_USEMODE) {
            fmi2_logf(&INS->base, fmi2Error, "logStatusError", "value reference %u is not an Integer variable", vr[i]);
            return fmi2Error;
        }
        if (mf_check_mode(value[i], msg, sizeof msg) != MF_OK) {
            fmi2_logf(&INS->base, fmi2Error, "logStatusError", "%s", msg);
            return fmi2Error;
        }
        INS->use_mode = value[i];
        INS->kin_ok = INS->out_ok = 0;
    }
    return fmi2OK;
}

/* ------------------------------------------------------------------ Model Exchange */

FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    if (!c || nx != 2 || !x) return fmi2Error;
    INS->x[0] = x[0];
    INS->x[1] = x[1];
    INS->out_ok = 0;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    if (!c || nx != 2 || !x) return fmi2Error;
    x[0] = INS->x[0];
    x[1] = INS->x[1];
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    if (!c || nx != 2 || !dx) return fmi2Error;
    if (update_kin(INS)) return fmi2Error;
    mt_rates(&INS->params, &INS->kin, INS->x, dx);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real xn[], size_t nx)
{
    if (!c || nx != 2 || !xn) return fmi2Error;
    xn[0] = xn[1] = 1e-3; /* deflections of the order of a millimetre */
    return fmi2OK;
}

/* ------------------------------------------------------------------ Co-Simulation */

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    double H = communicationStepSize;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c) return fmi2Error;
    if (!(H >= 0.0)) {
        fmi2_logf(&INS->base, fmi2Error, "logStatusError", "fmi2DoStep: invalid step size %g", H);
        return fmi2Error;
    }
    if (update_kin(INS)) return fmi2Error; /* inputs are held over the step */
    mt_advance(&INS->params, &INS->kin, INS->x, H);
    INS->time = currentCommunicationPoint + H;
    INS->out_ok = 0; /* the outputs at the new state are computed when read */
    return fmi2OK;
}

