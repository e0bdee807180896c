/*
 * fmi2_wrapper.c -- FMI 2.0 Model Exchange and Co-Simulation over the model interface of fmu_model.h
 * (the steady-state tyre, mf_model.c, or the transient tyre, mt_model.c: whichever the FMU's fmu.c
 * includes before this file).  Nothing here depends on the tyre.  No Boolean or String variables,
 * event indicators, FMU states, directional derivatives or input derivatives.
 *
 * Uses the FMI 2.0 standard headers (fmi2Functions.h: the export restores the standard's
 * FMI2_FUNCTION_PREFIX, so several tyres link statically into one executable).
 */
#ifdef MF_FMU_UNITY /* a part of fmu.c (alone, for an importer that compiles every .c: nothing) */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_model.h"

typedef enum { FMI2_INSTANTIATED, FMI2_INIT, FMI2_RUNNING, FMI2_TERMINATED, FMI2_ERROR } FMI2State;

typedef struct {
    fmi2CallbackFunctions cb;     /* the importer's callbacks (copied) */
    char *name;                   /* instance name (allocated with cb.allocateMemory) */
    fmi2Type type;
    FMI2State state;
    int log_errors, log_warnings; /* categories logStatusError / logStatusWarning on */
    FMModel *model;               /* allocated with cb.allocateMemory */
} Instance;

#define INS ((Instance *)c)

/* ------------------------------------------------------------------ logging */

/* The message is formatted here and passed as the format string with every '%' doubled, without variadic
 * arguments: a logger that formats (printf-style, as the standard asks) and a plain callback that does not
 * both show the same text. */
static void emit(const fmi2CallbackFunctions *cb, const char *name, fmi2Status status, const char *category,
                 const char *fmt, va_list ap)
{
    char buf[512], esc[1024];
    size_t i, j;
    vsnprintf(buf, sizeof buf, fmt, ap);
    for (i = j = 0; buf[i] && j + 2 < sizeof esc; i++) {
        if (buf[i] == '%') esc[j++] = '%';
        esc[j++] = buf[i];
    }
    esc[j] = '\0';
    cb->logger(cb->componentEnvironment, name, status, category, esc);
}

/* Log through the importer's logger, unless the category is switched off. */
static void wlogf(const Instance *ins, fmi2Status status, const char *category, const char *fmt, ...)
{
    va_list ap;
    if (!ins || !ins->cb.logger) return;
    if (status == fmi2Warning && !ins->log_warnings) return;
    if (status == fmi2Error && !ins->log_errors) return;
    va_start(ap, fmt);
    emit(&ins->cb, ins->name, status, category, fmt, ap);
    va_end(ap);
}

/* The model's logger (fmu_model.h). */
static void model_log(void *host, int status, const char *category, const char *message)
{
    wlogf((const Instance *)host, (fmi2Status)status, category, "%s", message);
}

/* Before an instance exists: straight to the importer's logger. */
static void log_early(const fmi2CallbackFunctions *cb, const char *name, const char *fmt, ...)
{
    va_list ap;
    if (!cb || !cb->logger) return;
    va_start(ap, fmt);
    emit(cb, name ? name : "", fmi2Error, "logStatusError", fmt, ap);
    va_end(ap);
}

static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    if (c) wlogf(INS, fmi2Error, "logStatusError", "%s is not supported", fn);
    return fmi2Error;
}

/* A call in a state where the standard does not allow it: an error (the instance stays usable). */
static fmi2Status wrong_state(fmi2Component c, const char *fn)
{
    static const char *const names[] = {"instantiated", "initialization mode", "running", "terminated", "error"};
    wlogf(INS, fmi2Error, "logStatusError", "%s is not allowed in state '%s'", fn, names[INS->state]);
    return fmi2Error;
}

/* Start of the value-access functions: a NULL component, or NULL arrays with n > 0, is an error. */
#define CHECK_ARRAYS(c, n, a, b)                                                                                  \
    do {                                                                                                          \
        if (!(c)) return fmi2Error;                                                                               \
        if ((n) > 0 && (!(a) || !(b))) {                                                                          \
            wlogf(INS, fmi2Error, "logStatusError", "%s: NULL array argument", __func__);                       \
            return fmi2Error;                                                                                     \
        }                                                                                                         \
    } while (0)

/* ------------------------------------------------------------------ life cycle */

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Instance *ins;
    const char *name = instanceName ? instanceName : "";
    (void)fmuResourceLocation;
    (void)visible;
    (void)loggingOn; /* warnings are rate-limited whatever the debug logging (fmu_model.h) */
    if (!functions || !functions->allocateMemory || !functions->freeMemory) {
        log_early(functions, name, "fmi2Instantiate: allocateMemory and freeMemory callbacks are required");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, fm_guid()) != 0) {
        log_early(functions, name, "fmi2Instantiate: wrong GUID %s (this binary is %s)", fmuGUID ? fmuGUID : "(null)",
                  fm_guid());
        return NULL;
    }
    ins = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!ins) return NULL;
    memset(ins, 0, sizeof *ins);
    ins->cb = *functions;
    ins->name = (char *)functions->allocateMemory(strlen(name) + 1, 1);
    ins->model = (FMModel *)functions->allocateMemory(1, fm_size());
    if (!ins->name || !ins->model) {
        if (ins->name) functions->freeMemory(ins->name);
        if (ins->model) functions->freeMemory(ins->model);
        functions->freeMemory(ins);
        return NULL;
    }
    strcpy(ins->name, name);
    ins->type = fmuType;
    ins->state = FMI2_INSTANTIATED;
    ins->log_errors = ins->log_warnings = 1;
    fm_init(ins->model, model_log, ins);
    return ins;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    fmi2CallbackFreeMemory fr;
    if (!c) return;
    fr = INS->cb.freeMemory;
    fr(INS->model);
    fr(INS->name);
    fr(c);
}

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[])
{
    size_t i;
    if (!c) return fmi2Error;
    if (nCategories == 0) {
        INS->log_errors = INS->log_warnings = 1;
        return fmi2OK;
    }
    for (i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (!cat) continue;
        if (strcmp(cat, "logAll") == 0) INS->log_errors = INS->log_warnings = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusWarning") == 0) INS->log_warnings = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusError") == 0) INS->log_errors = loggingOn ? 1 : 0;
        else {
            wlogf(INS, fmi2Error, "logStatusError", "unknown log category '%s'", cat);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (!c) return fmi2Error;
    if (INS->state != FMI2_INSTANTIATED) return wrong_state(c, "fmi2SetupExperiment");
    fm_set_time(INS->model, startTime);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    if (!c) return fmi2Error;
    if (INS->state != FMI2_INSTANTIATED) return wrong_state(c, "fmi2EnterInitializationMode");
    INS->state = FMI2_INIT;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    if (!c) return fmi2Error;
    if (INS->state != FMI2_INIT) return wrong_state(c, "fmi2ExitInitializationMode");
    if (fm_exit_initialization(INS->model) != FM_OK) { /* outputs are valid straight after initialisation */
        INS->state = FMI2_ERROR;
        return fmi2Error;
    }
    INS->state = FMI2_RUNNING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c)
{
    if (!c) return fmi2Error;
    INS->state = FMI2_TERMINATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c)
{
    if (!c) return fmi2Error;
    fm_reset(INS->model);
    INS->state = FMI2_INSTANTIATED;
    return fmi2OK;
}

/* ------------------------------------------------------------------ variables */

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (fm_get_real(INS->model, vr[i], &value[i]) != FM_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    size_t i;
    CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++) {
        int v = 0;
        if (fm_get_int(INS->model, vr[i], &v) != FM_OK) return fmi2Error;
        value[i] = v;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (fm_set_real(INS->model, vr[i], value[i]) != FM_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer value[])
{
    size_t i;
    CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (fm_set_int(INS->model, vr[i], value[i]) != FM_OK) return fmi2Error;
    return fmi2OK;
}

/* ------------------------------------------------------------------ no Boolean or String variables */

static fmi2Status no_vars(fmi2Component c, size_t n, const char *what)
{
    if (!c) return fmi2Error;
    if (n == 0) return fmi2OK;
    wlogf(INS, fmi2Error, "logStatusError", "the model has no %s variables", what);
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

/* ------------------------------------------------------------------ FMU state: not supported */

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

/* ------------------------------------------------------------------ Model Exchange: no events */

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
    fm_set_time(INS->model, time);
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ei[], size_t ni)
{
    (void)ei;
    return (c && ni == 0) ? fmi2OK : fmi2Error;
}

/* The continuous states (none for the steady-state tyre). */
static fmi2Status states_call(fmi2Component c, const char *fn, size_t nx, const void *array)
{
    if (!c) return fmi2Error;
    if (nx != fm_n_states() || (nx > 0 && !array)) {
        wlogf(INS, fmi2Error, "logStatusError", "%s: %u continuous states, not %u", fn, fm_n_states(), (unsigned)nx);
        return fmi2Error;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    if (states_call(c, "fmi2SetContinuousStates", nx, x) != fmi2OK) return fmi2Error;
    return nx ? (fmi2Status)fm_set_states(INS->model, x) : fmi2OK;
}

FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    if (states_call(c, "fmi2GetContinuousStates", nx, x) != fmi2OK) return fmi2Error;
    return nx ? (fmi2Status)fm_get_states(INS->model, x) : fmi2OK;
}

FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    if (states_call(c, "fmi2GetDerivatives", nx, dx) != fmi2OK) return fmi2Error;
    return nx ? (fmi2Status)fm_get_derivatives(INS->model, dx) : fmi2OK;
}

FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real xn[], size_t nx)
{
    if (states_call(c, "fmi2GetNominalsOfContinuousStates", nx, xn) != fmi2OK) return fmi2Error;
    if (nx) fm_get_nominals(xn);
    return fmi2OK;
}

/* ------------------------------------------------------------------ Co-Simulation */

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!c) return fmi2Error;
    if (INS->type != fmi2CoSimulation) return unsupported(c, "fmi2DoStep (Model Exchange instance)");
    if (INS->state != FMI2_RUNNING) return wrong_state(c, "fmi2DoStep");
    if (!(communicationStepSize >= 0.0)) {
        wlogf(INS, fmi2Error, "logStatusError", "fmi2DoStep: invalid step size %g", communicationStepSize);
        return fmi2Error;
    }
    return (fmi2Status)fm_do_step(INS->model, currentCommunicationPoint, communicationStepSize);
}

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
    *value = fm_time(INS->model);
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

#endif /* MF_FMU_UNITY */
