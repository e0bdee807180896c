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
#include "fmi_common.h"

typedef struct {
    FIInstance fi;            /* first: what both wrappers keep (fmi_common.h) */
    fmi2CallbackFunctions cb; /* the importer's callbacks (copied) */
    char *name;               /* instance name (allocated with cb.allocateMemory) */
} Instance;

#define INS ((Instance *)c)

/* ------------------------------------------------------------------ logging */

/* The message goes to the logger as the format string with every '%' doubled, without variadic arguments: a
 * logger that formats (printf-style, as the standard asks) and a plain callback that does not both show the
 * same text. */
static void log_to(const fmi2CallbackFunctions *cb, const char *name, int status, const char *category,
                   const char *message)
{
    char esc[1024];
    size_t i, j;
    if (!cb || !cb->logger) return;
    for (i = j = 0; message[i] && j + 2 < sizeof esc; i++) {
        if (message[i] == '%') esc[j++] = '%';
        esc[j++] = message[i];
    }
    esc[j] = '\0';
    cb->logger(cb->componentEnvironment, name ? name : "", (fmi2Status)status, category, esc);
}

/* fi_emit_fn of fmi_common.h. */
static void emit(const FIInstance *fi, int status, const char *category, const char *message)
{
    const Instance *ins = (const Instance *)fi;
    log_to(&ins->cb, ins->name, status, category, message);
}

static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    return (fmi2Status)fi_fail(FI(c), "%s is not supported", fn);
}

/* A function of the standard this FMU does not implement: NAME with the standard's parameter list PARAMS (the
 * first is the instance c), the others named unused after it; the call is refused, naming NAME. */
#define UNSUPPORTED(NAME, PARAMS, ...)                                                                           \
    FMI2_Export fmi2Status NAME PARAMS                                                                           \
    {                                                                                                            \
        __VA_ARGS__;                                                                                             \
        return unsupported(c, #NAME);                                                                            \
    }

/* ------------------------------------------------------------------ life cycle */

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Instance *ins;
    const char *name = instanceName ? instanceName : "";
    char msg[256];
    (void)fmuResourceLocation;
    (void)visible;
    (void)loggingOn; /* warnings are rate-limited whatever the debug logging (fmu_model.h) */
    if (!functions || !functions->allocateMemory || !functions->freeMemory) {
        log_to(functions, name, FM_ERROR, "logStatusError",
               "fmi2Instantiate: allocateMemory and freeMemory callbacks are required");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, fm_guid()) != 0) {
        snprintf(msg, sizeof msg, "fmi2Instantiate: wrong GUID %s (this binary is %s)", fmuGUID ? fmuGUID : "(null)",
                 fm_guid());
        log_to(functions, name, FM_ERROR, "logStatusError", msg);
        return NULL;
    }
    ins = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!ins) return NULL;
    memset(ins, 0, sizeof *ins);
    ins->cb = *functions;
    ins->name = (char *)functions->allocateMemory(strlen(name) + 1, 1);
    ins->fi.model = (FMModel *)functions->allocateMemory(1, fm_size());
    if (!ins->name || !ins->fi.model) {
        if (ins->name) functions->freeMemory(ins->name);
        if (ins->fi.model) functions->freeMemory(ins->fi.model);
        functions->freeMemory(ins);
        return NULL;
    }
    strcpy(ins->name, name);
    fi_init(&ins->fi, ins->fi.model, fmuType == fmi2CoSimulation, emit);
    return ins;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    fmi2CallbackFreeMemory fr;
    if (!c) return;
    fr = INS->cb.freeMemory;
    fr(INS->fi.model);
    fr(INS->name);
    fr(c);
}

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                                           const fmi2String categories[])
{
    return (fmi2Status)fi_set_debug_logging(FI(c), loggingOn, nCategories, categories);
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                                           fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (fi_in_state(FI(c), FI_INSTANTIATED, "fmi2SetupExperiment") != FM_OK) return fmi2Error;
    return (fmi2Status)fi_set_time(FI(c), startTime);
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    return (fmi2Status)fi_enter_initialization(FI(c), "fmi2EnterInitializationMode");
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    return (fmi2Status)fi_exit_initialization(FI(c), "fmi2ExitInitializationMode");
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c) { return (fmi2Status)fi_terminate(FI(c)); }
FMI2_Export fmi2Status fmi2Reset(fmi2Component c) { return (fmi2Status)fi_reset(FI(c)); }

/* ------------------------------------------------------------------ variables */

/* The value types are those fmi_common.h takes (fmi2ValueReference: unsigned int; fmi2Integer: int). */
FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    return (fmi2Status)fi_values(FI(c), "fmi2GetReal", FI_GET_REAL, vr, n, value);
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    return (fmi2Status)fi_values(FI(c), "fmi2GetInteger", FI_GET_INT, vr, n, value);
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    return (fmi2Status)fi_values(FI(c), "fmi2SetReal", FI_SET_REAL, vr, n, (void *)value);
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer value[])
{
    return (fmi2Status)fi_values(FI(c), "fmi2SetInteger", FI_SET_INT, vr, n, (void *)value);
}

/* ------------------------------------------------------------------ no Boolean or String variables */

static fmi2Status no_vars(fmi2Component c, size_t n, const char *what)
{
    if (!c) return fmi2Error;
    return n == 0 ? fmi2OK : (fmi2Status)fi_fail(FI(c), "the model has no %s variables", what);
}

/* Get or set (CONST: const) of a type the model has no variables of: an empty call is fine, any other an error. */
#define NO_VARIABLES(NAME, TYPE, CONST, WHAT)                                                                   \
    FMI2_Export fmi2Status NAME(fmi2Component c, const fmi2ValueReference vr[], size_t n, CONST TYPE value[])  \
    {                                                                                                           \
        (void)vr;                                                                                               \
        (void)value;                                                                                            \
        return no_vars(c, n, WHAT);                                                                             \
    }

NO_VARIABLES(fmi2GetBoolean, fmi2Boolean, , "Boolean")
NO_VARIABLES(fmi2SetBoolean, fmi2Boolean, const, "Boolean")
NO_VARIABLES(fmi2GetString, fmi2String, , "String")
NO_VARIABLES(fmi2SetString, fmi2String, const, "String")

/* ------------------------------------------------------------------ not supported: FMU states, derivatives */

UNSUPPORTED(fmi2GetFMUstate, (fmi2Component c, fmi2FMUstate *s), (void)s)
UNSUPPORTED(fmi2SetFMUstate, (fmi2Component c, fmi2FMUstate s), (void)s)
UNSUPPORTED(fmi2FreeFMUstate, (fmi2Component c, fmi2FMUstate *s), (void)s)
UNSUPPORTED(fmi2SerializedFMUstateSize, (fmi2Component c, fmi2FMUstate s, size_t *size), (void)s, (void)size)
UNSUPPORTED(fmi2SerializeFMUstate, (fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size), (void)s, (void)b,
            (void)size)
UNSUPPORTED(fmi2DeSerializeFMUstate, (fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s), (void)s,
            (void)b, (void)size)
UNSUPPORTED(fmi2GetDirectionalDerivative,
            (fmi2Component c, const fmi2ValueReference vU[], size_t nU, const fmi2ValueReference vK[], size_t nK,
             const fmi2Real dvK[], fmi2Real dvU[]),
            (void)vU, (void)nU, (void)vK, (void)nK, (void)dvK, (void)dvU)
UNSUPPORTED(fmi2SetRealInputDerivatives,
            (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[],
             const fmi2Real value[]),
            (void)vr, (void)n, (void)order, (void)value)
UNSUPPORTED(fmi2GetRealOutputDerivatives,
            (fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer order[], fmi2Real value[]),
            (void)vr, (void)n, (void)order, (void)value)
UNSUPPORTED(fmi2CancelStep, (fmi2Component c), (void)0)

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

FMI2_Export fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) { return (fmi2Status)fi_set_time(FI(c), time); }

FMI2_Export fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real ei[], size_t ni)
{
    (void)ei;
    return (c && ni == 0) ? fmi2OK : fmi2Error;
}

/* The continuous states (none for the steady-state tyre; fmi_common.h checks the count). */
FMI2_Export fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    return (fmi2Status)fi_set_states(FI(c), "fmi2SetContinuousStates", nx, x);
}
FMI2_Export fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    return (fmi2Status)fi_get_states(FI(c), "fmi2GetContinuousStates", nx, x);
}
FMI2_Export fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    return (fmi2Status)fi_get_derivatives(FI(c), "fmi2GetDerivatives", nx, dx);
}
FMI2_Export fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real xn[], size_t nx)
{
    return (fmi2Status)fi_get_nominals(FI(c), "fmi2GetNominalsOfContinuousStates", nx, xn);
}

/* ------------------------------------------------------------------ Co-Simulation */

FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                                  fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    return (fmi2Status)fi_do_step(FI(c), "fmi2DoStep", currentCommunicationPoint, communicationStepSize);
}

/* The status queries: the last successful time (of DoStep) and "not terminated" are the FMU's only answers;
 * any other kind is discarded. */
static fmi2Status status_of(fmi2Component c, const void *value, fmi2StatusKind s, fmi2StatusKind answered)
{
    if (!c || !value) return fmi2Error;
    return s == answered ? fmi2OK : fmi2Discard;
}

FMI2_Export fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    if (!c || !value) return fmi2Error;
    *value = fmi2OK;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    fmi2Status status = status_of(c, value, s, fmi2LastSuccessfulTime);
    if (status == fmi2OK) *value = fm_time(INS->fi.model);
    return status;
}

FMI2_Export fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    fmi2Status status = status_of(c, value, s, fmi2Terminated);
    if (status == fmi2OK) *value = fmi2False;
    return status;
}

FMI2_Export fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s, (void)value;
    return c ? fmi2Discard : fmi2Error;
}

FMI2_Export fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s, (void)value;
    return c ? fmi2Discard : fmi2Error;
}

#endif /* MF_FMU_UNITY */
