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
 * The value-reference table, start values and GUID come from mt_model_gen.h, generated
 * by mftire/fmu/transient_export.py from one variable table.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "mf_transient.h"
#include "mt_model_gen.h"

typedef enum { ST_INSTANTIATED, ST_INIT, ST_RUNNING, ST_TERMINATED, ST_ERROR } State;

#define WARN_REPEAT 10

typedef struct {
    MFParams params;
    MTInputs inputs;
    double x[2];
    MTKin kin;
    MTOutputs out;
    int kin_ok, out_ok;
    int use_mode;
    double time;
    fmi2CallbackFunctions cb;
    char *name;
    State state;
    int log_errors, log_warnings, debug_logging;
    unsigned warn_count[MF_W_COUNT];
} Instance;

#define INS ((Instance *)c)

/* Log through the importer's logger.  The message is formatted here and passed as the format
 * string with every '%' doubled, without variadic arguments: a logger that does not format (a
 * plain callback) and one that does (printf-style) both show the same text. */
static void logf_(Instance *ins, fmi2Status status, const char *category, const char *fmt, ...)
{
    char buf[512], esc[1024];
    size_t i, j;
    va_list ap;
    if (!ins || !ins->cb.logger) return;
    if (status == fmi2Warning && !ins->log_warnings) return;
    if (status == fmi2Error && !ins->log_errors) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    for (i = j = 0; buf[i] && j + 2 < sizeof esc; i++) {
        if (buf[i] == '%') esc[j++] = '%';
        esc[j++] = buf[i];
    }
    esc[j] = '\0';
    ins->cb.logger(ins->cb.componentEnvironment, ins->name, status, category, esc);
}

static void on_warning(void *ctx, int kind, const char *message)
{
    Instance *ins = (Instance *)ctx;
    unsigned n;
    if (kind == MF_W_LOW_SPEED) return; /* the transient model replaces MFeval's low-speed mode */
    n = ++ins->warn_count[kind];
    if (ins->debug_logging || n <= WARN_REPEAT)
        logf_(ins, fmi2Warning, "logStatusWarning", "t=%.17g: %s", ins->time, message);
    if (!ins->debug_logging && n == WARN_REPEAT)
        logf_(ins, fmi2Warning, "logStatusWarning", "this warning is now muted (enable debug logging to see all)");
}

static void reset(Instance *ins)
{
    ins->params = MT_PARAM_START;
    ins->inputs = MT_INPUT_START;
    ins->x[0] = MT_STATE_START[0];
    ins->x[1] = MT_STATE_START[1];
    ins->use_mode = MT_USEMODE_START;
    ins->time = 0.0;
    ins->kin_ok = ins->out_ok = 0;
    memset(ins->warn_count, 0, sizeof ins->warn_count);
}

static int bad_code(Instance *ins, int rc)
{
    char msg[256];
    if (rc == MF_BAD_MODE) mf_check_mode(ins->use_mode, msg, sizeof msg);
    else mf_check_fittyp(&ins->params, msg, sizeof msg);
    logf_(ins, fmi2Error, "logStatusError", "%s", msg);
    return 1;
}

static int update_kin(Instance *ins)
{
    int rc;
    if (ins->kin_ok) return 0;
    rc = mt_kinematics(&ins->params, ins->use_mode, &ins->inputs, &ins->kin, on_warning, ins);
    if (rc != MF_OK) return bad_code(ins, rc);
    ins->kin_ok = 1;
    return 0;
}

static int update_out(Instance *ins)
{
    int rc;
    if (ins->out_ok) return 0;
    if (update_kin(ins)) return 1;
    rc = mt_outputs(&ins->params, ins->use_mode, &ins->kin, ins->x, &ins->out, on_warning, ins);
    if (rc != MF_OK) return bad_code(ins, rc);
    ins->out_ok = 1;
    return 0;
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
        if (update_out(ins)) return fmi2Error;
        *value = *(const double *)((const char *)&ins->out + v->offset);
        return fmi2OK;
    default: break;
    }
bad:
    logf_(ins, fmi2Error, "logStatusError", "value reference %u is not a Real variable", vr);
    return fmi2Error;
}

static fmi2Status set_real(Instance *ins, unsigned vr, double value)
{
    const MTVarInfo *v;
    if (vr >= MT_N_VARS) goto bad;
    v = &MT_VARS[vr];
    switch (v->kind) {
    case MT_K_INPUT:
        *(double *)((char *)&ins->inputs + v->offset) = value;
        ins->kin_ok = ins->out_ok = 0;
        return fmi2OK;
    case MT_K_PARAM:
        if (v->fixed && ins->state != ST_INSTANTIATED && ins->state != ST_INIT) {
            logf_(ins, fmi2Error, "logStatusError", "%s is a fixed parameter", MT_VAR_NAMES[vr]);
            return fmi2Error;
        }
        *(double *)((char *)&ins->params + v->offset) = value;
        ins->kin_ok = ins->out_ok = 0;
        return fmi2OK;
    case MT_K_STATE:
        if (ins->state == ST_RUNNING) {
            logf_(ins, fmi2Error, "logStatusError", "%s: set states with fmi2SetContinuousStates", MT_VAR_NAMES[vr]);
            return fmi2Error;
        }
        ins->x[v->offset] = value;
        ins->out_ok = 0;
        return fmi2OK;
    default:
        logf_(ins, fmi2Error, "logStatusError", "%s cannot be set", MT_VAR_NAMES[vr]);
        return fmi2Error;
    }
bad:
    logf_(ins, fmi2Error, "logStatusError", "value reference %u is not a Real variable", vr);
    return fmi2Error;
}

/* ------------------------------------------------------------------ common functions */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[])
{
    size_t i;
    if (!c) return fmi2Error;
    if (nCategories == 0) {
        INS->debug_logging = loggingOn ? 1 : 0;
        INS->log_errors = INS->log_warnings = 1;
        return fmi2OK;
    }
    for (i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (!cat) continue;
        if (strcmp(cat, "logAll") == 0) INS->debug_logging = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusWarning") == 0) INS->log_warnings = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusError") == 0) INS->log_errors = loggingOn ? 1 : 0;
        else {
            logf_(INS, fmi2Error, "logStatusError", "unknown log category '%s'", cat);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Instance *ins;
    (void)fmuResourceLocation;
    (void)visible;
    (void)fmuType;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    if (!fmuGUID || strcmp(fmuGUID, MT_GUID) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "fmi2Instantiate: wrong GUID %s (this binary is %s)", fmuGUID ? fmuGUID : "(null)",
                              MT_GUID);
        return NULL;
    }
    ins = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!ins) return NULL;
    memset(ins, 0, sizeof *ins);
    ins->cb = *functions;
    ins->name = (char *)functions->allocateMemory(strlen(instanceName ? instanceName : "") + 1, 1);
    if (!ins->name) {
        functions->freeMemory(ins);
        return NULL;
    }
    strcpy(ins->name, instanceName ? instanceName : "");
    ins->state = ST_INSTANTIATED;
    ins->log_errors = ins->log_warnings = 1;
    ins->debug_logging = loggingOn ? 1 : 0;
    reset(ins);
    return ins;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    fmi2CallbackFreeMemory fr;
    if (!c) return;
    fr = INS->cb.freeMemory;
    fr(INS->name);
    fr(c);
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (!c) return fmi2Error;
    INS->time = startTime;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    if (!c) return fmi2Error;
    INS->state = ST_INIT;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    char msg[256];
    if (!c) return fmi2Error;
    if (mf_check_fittyp(&INS->params, msg, sizeof msg) != MF_OK || mf_check_mode(INS->use_mode, msg, sizeof msg) != MF_OK) {
        logf_(INS, fmi2Error, "logStatusError", "%s", msg);
        INS->state = ST_ERROR;
        return fmi2Error;
    }
    if (INS->params.TR_CS_STEP <= 0.0 || INS->params.VXLOW <= 0.0) {
        logf_(INS, fmi2Error, "logStatusError", "TR_CS_STEP and VXLOW must be positive");
        INS->state = ST_ERROR;
        return fmi2Error;
    }
    if (update_out(INS)) {
        INS->state = ST_ERROR;
        return fmi2Error;
    }
    INS->state = ST_RUNNING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c)
{
    if (!c) return fmi2Error;
    INS->state = ST_TERMINATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c)
{
    if (!c) return fmi2Error;
    reset(INS);
    INS->state = ST_INSTANTIATED;
    return fmi2OK;
}

#define CHECK_ARRAYS(a, b)                                                                   \
    do {                                                                                     \
        if (!c) return fmi2Error;                                                            \
        if (n > 0 && (!(a) || !(b))) {                                                       \
            logf_(INS, fmi2Error, "logStatusError", "%s: NULL array argument", __func__);    \
            return fmi2Error;                                                                \
        }                                                                                    \
    } while (0)

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    CHECK_ARRAYS(vr, value);
    for (i = 0; i < n; i++)
        if (get_real(INS, vr[i], &value[i]) != fmi2OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    CHECK_ARRAYS(vr, value);
    for (i = 0; i < n; i++)
        if (set_real(INS, vr[i], value[i]) != fmi2OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    size_t i;
    CHECK_ARRAYS(vr, value);
    for (i = 0; i < n; i++) {
        if (vr[i] != MT_VR_USEMODE) {
            logf_(INS, fmi2Error, "logStatusError", "value reference %u is not an Integer variable", vr[i]);
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
    CHECK_ARRAYS(vr, value);
    for (i = 0; i < n; i++) {
        if (vr[i] != MT_VR_USEMODE) {
            logf_(INS, fmi2Error, "logStatusError", "value reference %u is not an Integer variable", vr[i]);
            return fmi2Error;
        }
        if (mf_check_mode(value[i], msg, sizeof msg) != MF_OK) {
            logf_(INS, fmi2Error, "logStatusError", "%s", msg);
            return fmi2Error;
        }
        INS->use_mode = value[i];
        INS->kin_ok = INS->out_ok = 0;
    }
    return fmi2OK;
}

static fmi2Status no_vars(fmi2Component c, size_t n, const char *what)
{
    if (!c) return fmi2Error;
    if (n == 0) return fmi2OK;
    logf_(INS, fmi2Error, "logStatusError", "the model has no %s variables", what);
    return fmi2Error;
}

FMI2_Export fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return no_vars(c, n, "Boolean");
}
FMI2_Export fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    return no_vars(c, n, "Boolean");
}
FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_vars(c, n, "String");
}
FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String value[])
{
    (void)vr;
    (void)value;
    return no_vars(c, n, "String");
}

static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    if (c) logf_(INS, fmi2Error, "logStatusError", "%s is not supported", fn);
    return fmi2Error;
}

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s)
{
    (void)s;
    return unsupported(c, "fmi2GetFMUstate");
}
FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{
    (void)s;
    return unsupported(c, "fmi2SetFMUstate");
}
FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s)
{
    (void)s;
    return unsupported(c, "fmi2FreeFMUstate");
}
FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size)
{
    (void)s;
    (void)size;
    return unsupported(c, "fmi2SerializedFMUstateSize");
}
FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size)
{
    (void)s;
    (void)b;
    (void)size;
    return unsupported(c, "fmi2SerializeFMUstate");
}
FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s)
{
    (void)s;
    (void)b;
    (void)size;
    return unsupported(c, "fmi2DeSerializeFMUstate");
}
FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vU[], size_t nU,
                                                    const fmi2ValueReference vK[], size_t nK, const fmi2Real dvK[],
                                                    fmi2Real dvU[])
{
    (void)vU;
    (void)nU;
    (void)vK;
    (void)nK;
    (void)dvK;
    (void)dvU;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

/* ------------------------------------------------------------------ Model Exchange */

FMI2_Export fmi2Status fmi2EnterEventMode(fmi2Component c) { return c ? fmi2OK : fmi2Error; }

FMI2_Export fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    if (!c || !info) return fmi2Error;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return c ? fmi2OK : fmi2Error; }

FMI2_Export fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c) return fmi2Error;
    if (enterEventMode) *enterEventMode = fmi2False;
    if (terminateSimulation) *terminateSimulation = fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    if (!c) return fmi2Error;
    INS->time = time;
    return fmi2OK;
}

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

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ei[], size_t ni)
{
    (void)ei;
    return (c && ni == 0) ? fmi2OK : fmi2Error;
}

/* ------------------------------------------------------------------ Co-Simulation */

FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                   const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr;
    (void)n;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                    const fmi2Integer order[], fmi2Real value[])
{
    (void)vr;
    (void)n;
    (void)order;
    (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    double H = communicationStepSize;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c) return fmi2Error;
    if (!(H >= 0.0)) {
        logf_(INS, fmi2Error, "logStatusError", "fmi2DoStep: invalid step size %g", H);
        return fmi2Error;
    }
    if (update_kin(INS)) return fmi2Error; /* inputs are held over the step */
    mt_advance(&INS->params, &INS->kin, INS->x, H);
    INS->time = currentCommunicationPoint + H;
    INS->out_ok = 0;
    return update_out(INS) ? fmi2Error : fmi2OK;
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }

FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    if (!c || !value) return fmi2Error;
    *value = fmi2OK;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    if (!c || !value) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = INS->time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    if (!c || !value) return fmi2Error;
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return c ? fmi2Discard : fmi2Error;
}
