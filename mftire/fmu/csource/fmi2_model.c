/*
 * fmi2_model.c -- FMI 2.0 Model Exchange and Co-Simulation wrapper of the mftire
 * Magic Formula evaluator (mf_eval.c).  The tyre is algebraic: no continuous
 * states, no event indicators; every output depends directly on every input.
 *
 * Uses the FMI 2.0 standard headers (fmi2Functions.h and friends).
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "mf_model.h"

typedef enum { ST_INSTANTIATED, ST_INIT, ST_RUNNING, ST_TERMINATED, ST_ERROR } State;

typedef struct {
    MFModel model;
    fmi2CallbackFunctions cb;
    char *name;
    fmi2Type type;
    State state;
    int log_errors, log_warnings;
} Instance;

static void log_cb(MFModel *m, int status, const char *category, const char *message)
{
    Instance *ins = (Instance *)m->host;
    if (!ins || !ins->cb.logger) return;
    if (status == MF_STATUS_WARNING && !ins->log_warnings) return;
    if (status == MF_STATUS_ERROR && !ins->log_errors) return;
    ins->cb.logger(ins->cb.componentEnvironment, ins->name, (fmi2Status)status, category, "%s", message);
}

#define INS ((Instance *)c)
#define CHECK_NULL(p, what)                                                                                 \
    do {                                                                                                    \
        if (!(p) && n > 0) {                                                                                \
            mf_model_logf(&INS->model, MF_STATUS_ERROR, "logStatusError", "%s: NULL array argument", what); \
            return fmi2Error;                                                                               \
        }                                                                                                   \
    } while (0)

/* ------------------------------------------------------------------ common functions */

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[])
{
    size_t i;
    if (!c) return fmi2Error;
    if (nCategories == 0) {
        INS->model.debug_logging = loggingOn ? 1 : 0;
        INS->log_errors = INS->log_warnings = 1;
        return fmi2OK;
    }
    for (i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (!cat) continue;
        if (strcmp(cat, "logAll") == 0) INS->model.debug_logging = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusWarning") == 0) INS->log_warnings = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusError") == 0) INS->log_errors = loggingOn ? 1 : 0;
        else {
            mf_model_logf(&INS->model, MF_STATUS_ERROR, "logStatusError", "unknown log category '%s'", cat);
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
    if (!functions || !functions->allocateMemory || !functions->freeMemory) {
        if (functions && functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "fmi2Instantiate: allocateMemory and freeMemory callbacks are required");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, mf_model_guid()) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "fmi2Instantiate: wrong GUID %s (this binary is %s)", fmuGUID ? fmuGUID : "(null)",
                              mf_model_guid());
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
    ins->type = fmuType;
    ins->state = ST_INSTANTIATED;
    ins->log_errors = ins->log_warnings = 1;
    mf_model_init(&ins->model, log_cb, ins);
    ins->model.debug_logging = loggingOn ? 1 : 0;
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
    INS->model.time = startTime;
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
    if (!c) return fmi2Error;
    /* outputs are valid straight after initialisation */
    if (mf_model_validate(&INS->model) != MF_STATUS_OK || mf_model_update(&INS->model) != MF_STATUS_OK) {
        INS->state = ST_ERROR;
        return fmi2Error;
    }
    INS->model.initialized = 1;
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
    mf_model_reset(&INS->model);
    INS->state = ST_INSTANTIATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    if (!c) return fmi2Error;
    CHECK_NULL(vr, "fmi2GetReal");
    CHECK_NULL(value, "fmi2GetReal");
    for (i = 0; i < n; i++)
        if (mf_model_get_real(&INS->model, vr[i], &value[i]) != MF_STATUS_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    size_t i;
    if (!c) return fmi2Error;
    CHECK_NULL(vr, "fmi2GetInteger");
    CHECK_NULL(value, "fmi2GetInteger");
    for (i = 0; i < n; i++) {
        int v;
        if (mf_model_get_int(&INS->model, vr[i], &v) != MF_STATUS_OK) return fmi2Error;
        value[i] = v;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean value[])
{
    (void)vr;
    (void)value;
    if (!c) return fmi2Error;
    if (n == 0) return fmi2OK;
    mf_model_logf(&INS->model, MF_STATUS_ERROR, "logStatusError", "the model has no Boolean variables");
    return fmi2Error;
}

FMI2_Export fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String value[])
{
    (void)vr;
    (void)value;
    if (!c) return fmi2Error;
    if (n == 0) return fmi2OK;
    mf_model_logf(&INS->model, MF_STATUS_ERROR, "logStatusError", "the model has no String variables");
    return fmi2Error;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    if (!c) return fmi2Error;
    CHECK_NULL(vr, "fmi2SetReal");
    CHECK_NULL(value, "fmi2SetReal");
    for (i = 0; i < n; i++)
        if (mf_model_set_real(&INS->model, vr[i], value[i]) != MF_STATUS_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer value[])
{
    size_t i;
    if (!c) return fmi2Error;
    CHECK_NULL(vr, "fmi2SetInteger");
    CHECK_NULL(value, "fmi2SetInteger");
    for (i = 0; i < n; i++)
        if (mf_model_set_int(&INS->model, vr[i], value[i]) != MF_STATUS_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Boolean value[])
{
    return fmi2GetBoolean(c, vr, n, (fmi2Boolean *)value);
}

FMI2_Export fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String value[])
{
    return fmi2GetString(c, vr, n, (fmi2String *)value);
}

/* FMU state: not supported (canGetAndSetFMUstate is false). */
static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    if (c) mf_model_logf(&INS->model, MF_STATUS_ERROR, "logStatusError", "%s is not supported", fn);
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
    INS->model.time = time;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    (void)x;
    return (c && nx == 0) ? fmi2OK : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    (void)dx;
    return (c && nx == 0) ? fmi2OK : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ei[], size_t ni)
{
    (void)ei;
    return (c && ni == 0) ? fmi2OK : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    (void)x;
    return (c && nx == 0) ? fmi2OK : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real xn[], size_t nx)
{
    (void)xn;
    return (c && nx == 0) ? fmi2OK : fmi2Error;
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
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c) return fmi2Error;
    if (communicationStepSize < 0.0) {
        mf_model_logf(&INS->model, MF_STATUS_ERROR, "logStatusError", "fmi2DoStep: negative step size %g",
                      communicationStepSize);
        return fmi2Error;
    }
    /* inputs are held over the step; the outputs at its end are those of the inputs */
    INS->model.time = currentCommunicationPoint + communicationStepSize;
    return mf_model_update(&INS->model) == MF_STATUS_OK ? fmi2OK : fmi2Error;
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
    *value = INS->model.time;
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
