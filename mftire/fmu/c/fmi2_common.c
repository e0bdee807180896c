/*
 * fmi2_common.c -- the FMI 2.0 functions that do not depend on the model, shared by the
 * steady-state (fmi2_model.c) and the transient (fmi2_transient.c) wrappers; see
 * fmi2_common.h.  Neither tyre has Boolean or String variables, event indicators, FMU
 * states, directional derivatives or input derivatives.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_common.h"

#define B FMI2_BASE(c)

/* ------------------------------------------------------------------ logging */

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

void fmi2_logf(const FMI2Base *b, fmi2Status status, const char *category, const char *fmt, ...)
{
    va_list ap;
    if (!b || !b->cb.logger) return;
    if (status == fmi2Warning && !b->log_warnings) return;
    if (status == fmi2Error && !b->log_errors) return;
    va_start(ap, fmt);
    emit(&b->cb, b->name, status, category, fmt, ap);
    va_end(ap);
}

void fmi2_log(const FMI2Base *b, fmi2Status status, const char *category, const char *message)
{
    fmi2_logf(b, status, category, "%s", message);
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

fmi2Status fmi2_unsupported(fmi2Component c, const char *fn)
{
    if (c) fmi2_logf(B, fmi2Error, "logStatusError", "%s is not supported", fn);
    return fmi2Error;
}

/* ------------------------------------------------------------------ life cycle */

FMI2Base *fmi2_base_new(size_t size, fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                        const char *expected_guid, const fmi2CallbackFunctions *functions)
{
    FMI2Base *b;
    const char *name = instanceName ? instanceName : "";
    if (!functions || !functions->allocateMemory || !functions->freeMemory) {
        log_early(functions, name, "fmi2Instantiate: allocateMemory and freeMemory callbacks are required");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, expected_guid) != 0) {
        log_early(functions, name, "fmi2Instantiate: wrong GUID %s (this binary is %s)",
                  fmuGUID ? fmuGUID : "(null)", expected_guid);
        return NULL;
    }
    b = (FMI2Base *)functions->allocateMemory(1, size);
    if (!b) return NULL;
    memset(b, 0, size);
    b->cb = *functions;
    b->name = (char *)functions->allocateMemory(strlen(name) + 1, 1);
    if (!b->name) {
        functions->freeMemory(b);
        return NULL;
    }
    strcpy(b->name, name);
    b->type = fmuType;
    b->state = FMI2_INSTANTIATED;
    b->log_errors = b->log_warnings = 1;
    return b;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c)
{
    fmi2CallbackFreeMemory fr;
    if (!c) return;
    fr = B->cb.freeMemory;
    fr(B->name);
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
        *B->debug_logging = loggingOn ? 1 : 0;
        B->log_errors = B->log_warnings = 1;
        return fmi2OK;
    }
    for (i = 0; i < nCategories; i++) {
        const char *cat = categories[i];
        if (!cat) continue;
        if (strcmp(cat, "logAll") == 0) *B->debug_logging = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusWarning") == 0) B->log_warnings = loggingOn ? 1 : 0;
        else if (strcmp(cat, "logStatusError") == 0) B->log_errors = loggingOn ? 1 : 0;
        else {
            fmi2_logf(B, fmi2Error, "logStatusError", "unknown log category '%s'", cat);
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
    *B->time = startTime;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    if (!c) return fmi2Error;
    B->state = FMI2_INIT;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c)
{
    if (!c) return fmi2Error;
    B->state = FMI2_TERMINATED;
    return fmi2OK;
}

/* ------------------------------------------------------------------ no Boolean or String variables */

static fmi2Status no_vars(fmi2Component c, size_t n, const char *what)
{
    if (!c) return fmi2Error;
    if (n == 0) return fmi2OK;
    fmi2_logf(B, fmi2Error, "logStatusError", "the model has no %s variables", what);
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
    return fmi2_unsupported(c, "fmi2GetFMUstate");
}
FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s)
{
    (void)s;
    return fmi2_unsupported(c, "fmi2SetFMUstate");
}
FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s)
{
    (void)s;
    return fmi2_unsupported(c, "fmi2FreeFMUstate");
}
FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size)
{
    (void)s;
    (void)size;
    return fmi2_unsupported(c, "fmi2SerializedFMUstateSize");
}
FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size)
{
    (void)s;
    (void)b;
    (void)size;
    return fmi2_unsupported(c, "fmi2SerializeFMUstate");
}
FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s)
{
    (void)s;
    (void)b;
    (void)size;
    return fmi2_unsupported(c, "fmi2DeSerializeFMUstate");
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
    return fmi2_unsupported(c, "fmi2GetDirectionalDerivative");
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
    *B->time = time;
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
    return fmi2_unsupported(c, "fmi2SetRealInputDerivatives");
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                                    const fmi2Integer order[], fmi2Real value[])
{
    (void)vr;
    (void)n;
    (void)order;
    (void)value;
    return fmi2_unsupported(c, "fmi2GetRealOutputDerivatives");
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c) { return fmi2_unsupported(c, "fmi2CancelStep"); }

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
    *value = *B->time;
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
