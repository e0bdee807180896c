/*
 * fmi3_wrapper.c -- FMI 3.0 Model Exchange and Co-Simulation over the model interface of fmu_model.h
 * (the steady-state tyre, mf_model.c, or the transient tyre, mt_model.c: whichever the FMU's fmu.c
 * includes before this file).  Nothing here depends on the tyre.  No event indicators, no clocks.
 *
 * Uses the FMI 3.0 standard headers (fmi3Functions.h and friends; FMI3_FUNCTION_PREFIX honoured).
 */
#ifdef MF_FMU_UNITY /* a part of fmu.c (alone, for an importer that compiles every .c: nothing) */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmi_common.h"

typedef struct {
    FIInstance fi; /* first: what both wrappers keep (fmi_common.h) */
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
    char *name;
} Instance;

#define INS ((Instance *)instance)

/* fi_emit_fn of fmi_common.h. */
static void emit(const FIInstance *fi, int status, const char *category, const char *message)
{
    const Instance *ins = (const Instance *)fi;
    if (ins->logger) ins->logger(ins->env, (fmi3Status)status, category, message);
}

static fmi3Status fail(fmi3Instance instance, const char *what)
{
    return (fmi3Status)fi_fail(FI(instance), "%s", what);
}

/* A function of the standard this FMU does not implement: NAME with the standard's parameter list PARAMS (the
 * first is the instance), the others named unused after WHY; the call is refused with the error WHY. */
#define REFUSED(NAME, PARAMS, WHY, ...)                                                                          \
    FMI3_Export fmi3Status NAME PARAMS                                                                           \
    {                                                                                                            \
        __VA_ARGS__;                                                                                             \
        return fail(instance, WHY);                                                                              \
    }
#define UNSUPPORTED(NAME, PARAMS, ...) REFUSED(NAME, PARAMS, #NAME " is not supported", __VA_ARGS__)

#define NO_CLOCKS_TEXT "the model has no clocks"

/* Access to variables of a kind the model has none of (nvr value references): an empty call is fine, any other
 * the error WHY. */
#define NO_VALUES(NAME, PARAMS, WHY, ...)                                                                        \
    FMI3_Export fmi3Status NAME PARAMS                                                                           \
    {                                                                                                            \
        __VA_ARGS__;                                                                                             \
        if (!instance) return fmi3Error;                                                                         \
        return nvr == 0 ? fmi3OK : fail(instance, WHY);                                                          \
    }

static Instance *create(fmi3String name, fmi3String token, fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                        fmi3LogMessageCallback logger, int cosim)
{
    Instance *ins;
    FMModel *model;
    (void)loggingOn; /* warnings are rate-limited whatever the debug logging (fmu_model.h) */
    if (!token || strcmp(token, fm_guid()) != 0) {
        if (logger) logger(env, fmi3Error, "logStatusError", "wrong instantiationToken for this binary");
        return NULL;
    }
    ins = (Instance *)calloc(1, sizeof(Instance));
    if (!ins) return NULL;
    ins->name = (char *)malloc(strlen(name ? name : "") + 1);
    model = (FMModel *)calloc(1, fm_size());
    if (!ins->name || !model) {
        free(ins->name);
        free(model);
        free(ins);
        return NULL;
    }
    strcpy(ins->name, name ? name : "");
    ins->env = env;
    ins->logger = logger;
    fi_init(&ins->fi, model, cosim, emit);
    return ins;
}

/* ------------------------------------------------------------------ common functions */

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

FMI3_Export fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                                           const fmi3String categories[])
{
    return (fmi3Status)fi_set_debug_logging(FI(instance), loggingOn, nCategories, categories);
}

FMI3_Export fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                                      fmi3LogMessageCallback logMessage)
{
    (void)resourcePath;
    (void)visible;
    return create(instanceName, instantiationToken, loggingOn, instanceEnvironment, logMessage, 0);
}

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
    const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables,
    fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
    fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)resourcePath;
    (void)visible;
    (void)eventModeUsed;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    return create(instanceName, instantiationToken, loggingOn, instanceEnvironment, logMessage, 1);
}

FMI3_Export fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
    fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
    fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption,
    fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError", "Scheduled Execution is not supported");
    return NULL;
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance)
{
    if (!instance) return;
    free(INS->fi.model);
    free(INS->name);
    free(instance);
}

FMI3_Export fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (fi_enter_initialization(FI(instance), "fmi3EnterInitializationMode") != FM_OK) return fmi3Error;
    return (fmi3Status)fi_set_time(FI(instance), startTime);
}

FMI3_Export fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    return (fmi3Status)fi_exit_initialization(FI(instance), "fmi3ExitInitializationMode");
}

FMI3_Export fmi3Status fmi3EnterEventMode(fmi3Instance instance) { return instance ? fmi3OK : fmi3Error; }

FMI3_Export fmi3Status fmi3Terminate(fmi3Instance instance) { return (fmi3Status)fi_terminate(FI(instance)); }
FMI3_Export fmi3Status fmi3Reset(fmi3Instance instance) { return (fmi3Status)fi_reset(FI(instance)); }

/* ------------------------------------------------------------------ variables */

/* The Float64 and Int32 variables, scalar only (nValues == nValueReferences), through fmi_common.h, which takes
 * value references as unsigned and Int32 values as int: the sizes are checked here (a negative array size). */
typedef char fmi3_value_reference_is_unsigned[sizeof(fmi3ValueReference) == sizeof(unsigned) ? 1 : -1];
typedef char fmi3_int32_is_int[sizeof(fmi3Int32) == sizeof(int) ? 1 : -1];

static fmi3Status scalars(fmi3Instance instance, const char *fn, FIAccess access, const fmi3ValueReference vr[],
                          size_t nvr, void *values, size_t nValues)
{
    if (!instance) return fmi3Error;
    if (nValues != nvr)
        return (fmi3Status)fi_fail(FI(instance), "%s: only scalar variables (nValues == nValueReferences)", fn);
    return (fmi3Status)fi_values(FI(instance), fn, access, (const unsigned *)vr, nvr, values);
}

/* Get or set (CONST: const) of the variables of one type, through scalars(). */
#define SCALARS(NAME, TYPE, CONST, ACCESS)                                                                      \
    FMI3_Export fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,               \
                                CONST TYPE values[], size_t nValues)                                            \
    {                                                                                                           \
        return scalars(instance, #NAME, ACCESS, vr, nvr, (void *)values, nValues);                             \
    }

SCALARS(fmi3GetFloat64, fmi3Float64, , FI_GET_REAL)
SCALARS(fmi3SetFloat64, fmi3Float64, const, FI_SET_REAL)
SCALARS(fmi3GetInt32, fmi3Int32, , FI_GET_INT)
SCALARS(fmi3SetInt32, fmi3Int32, const, FI_SET_INT)

/* Types the model does not use. */
#define NO_VARIABLES(NAME, TYPE, CONST)                                                                         \
    NO_VALUES(NAME, (fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, CONST TYPE values[],      \
                     size_t nValues),                                                                           \
              #NAME ": the model has no variables of this type", (void)vr, (void)values, (void)nValues)

NO_VARIABLES(fmi3GetFloat32, fmi3Float32, )
NO_VARIABLES(fmi3GetInt8, fmi3Int8, )
NO_VARIABLES(fmi3GetUInt8, fmi3UInt8, )
NO_VARIABLES(fmi3GetInt16, fmi3Int16, )
NO_VARIABLES(fmi3GetUInt16, fmi3UInt16, )
NO_VARIABLES(fmi3GetUInt32, fmi3UInt32, )
NO_VARIABLES(fmi3GetInt64, fmi3Int64, )
NO_VARIABLES(fmi3GetUInt64, fmi3UInt64, )
NO_VARIABLES(fmi3GetBoolean, fmi3Boolean, )
NO_VARIABLES(fmi3GetString, fmi3String, )
NO_VARIABLES(fmi3SetFloat32, fmi3Float32, const)
NO_VARIABLES(fmi3SetInt8, fmi3Int8, const)
NO_VARIABLES(fmi3SetUInt8, fmi3UInt8, const)
NO_VARIABLES(fmi3SetInt16, fmi3Int16, const)
NO_VARIABLES(fmi3SetUInt16, fmi3UInt16, const)
NO_VARIABLES(fmi3SetUInt32, fmi3UInt32, const)
NO_VARIABLES(fmi3SetInt64, fmi3Int64, const)
NO_VARIABLES(fmi3SetUInt64, fmi3UInt64, const)
NO_VARIABLES(fmi3SetBoolean, fmi3Boolean, const)
NO_VARIABLES(fmi3SetString, fmi3String, const)
NO_VALUES(fmi3GetBinary, (fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                          fmi3Binary values[], size_t nValues),
          "the model has no Binary variables", (void)vr, (void)valueSizes, (void)values, (void)nValues)
NO_VALUES(fmi3SetBinary, (fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const size_t valueSizes[], const fmi3Binary values[], size_t nValues),
          "the model has no Binary variables", (void)vr, (void)valueSizes, (void)values, (void)nValues)
NO_VALUES(fmi3GetClock, (fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]),
          NO_CLOCKS_TEXT, (void)vr, (void)values)
NO_VALUES(fmi3SetClock, (fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3Clock values[]),
          NO_CLOCKS_TEXT, (void)vr, (void)values)

/* Every output (and state derivative) depends on every input and state (fm_dependencies). */
#define is_output(vr) fm_is_unknown(vr)

FMI3_Export fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                                           size_t *nDependencies)
{
    if (!instance || !nDependencies) return fmi3Error;
    *nDependencies = is_output(vr) ? fm_dependencies(NULL, 0) : 0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                                   size_t elementIndicesOfDependent[],
                                                   fmi3ValueReference independents[],
                                                   size_t elementIndicesOfIndependents[],
                                                   fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    unsigned inputs[64];
    size_t i, n;
    if (!instance) return fmi3Error;
    n = fm_dependencies(inputs, 64);
    if (n > 64) return fail(instance, "fmi3GetVariableDependencies: more than 64 dependencies");
    if (!is_output(dependent) || nDependencies != n) return nDependencies == 0 ? fmi3OK : fmi3Error;
    for (i = 0; i < n; i++) {
        elementIndicesOfDependent[i] = 0;
        independents[i] = (fmi3ValueReference)inputs[i];
        elementIndicesOfIndependents[i] = 0;
        dependencyKinds[i] = fmi3Dependent;
    }
    return fmi3OK;
}

/* ------------------------------------------------------------------ not supported */

UNSUPPORTED(fmi3GetFMUState, (fmi3Instance instance, fmi3FMUState *s), (void)s)
UNSUPPORTED(fmi3SetFMUState, (fmi3Instance instance, fmi3FMUState s), (void)s)
UNSUPPORTED(fmi3FreeFMUState, (fmi3Instance instance, fmi3FMUState *s), (void)s)
UNSUPPORTED(fmi3SerializedFMUStateSize, (fmi3Instance instance, fmi3FMUState s, size_t *size), (void)s, (void)size)
UNSUPPORTED(fmi3SerializeFMUState, (fmi3Instance instance, fmi3FMUState s, fmi3Byte b[], size_t size), (void)s,
            (void)b, (void)size)
UNSUPPORTED(fmi3DeserializeFMUState, (fmi3Instance instance, const fmi3Byte b[], size_t size, fmi3FMUState *s),
            (void)s, (void)b, (void)size)
UNSUPPORTED(fmi3GetDirectionalDerivative,
            (fmi3Instance instance, const fmi3ValueReference u[], size_t nu, const fmi3ValueReference k[], size_t nk,
             const fmi3Float64 seed[], size_t ns, fmi3Float64 sens[], size_t nsens),
            (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)sens, (void)nsens)
UNSUPPORTED(fmi3GetAdjointDerivative,
            (fmi3Instance instance, const fmi3ValueReference u[], size_t nu, const fmi3ValueReference k[], size_t nk,
             const fmi3Float64 seed[], size_t ns, fmi3Float64 sens[], size_t nsens),
            (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)sens, (void)nsens)
UNSUPPORTED(fmi3GetOutputDerivatives,
            (fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 orders[],
             fmi3Float64 values[], size_t nValues),
            (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues)
REFUSED(fmi3EnterConfigurationMode, (fmi3Instance instance), "the model has no structural parameters", (void)0)
REFUSED(fmi3ExitConfigurationMode, (fmi3Instance instance), "the model has no structural parameters", (void)0)
REFUSED(fmi3ActivateModelPartition,
        (fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime),
        "Scheduled Execution is not supported", (void)clockReference, (void)activationTime)

/* The clocks' intervals and shifts: the model has no clocks. */
#define NO_CLOCKS(NAME, PARAMS, ...) REFUSED(NAME, PARAMS, NO_CLOCKS_TEXT, __VA_ARGS__)

NO_CLOCKS(fmi3GetIntervalDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                   fmi3Float64 intervals[], fmi3IntervalQualifier q[]),
          (void)vr, (void)n, (void)intervals, (void)q)
NO_CLOCKS(fmi3GetIntervalFraction, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[],
                                    fmi3UInt64 r[], fmi3IntervalQualifier q[]),
          (void)vr, (void)n, (void)c, (void)r, (void)q)
NO_CLOCKS(fmi3GetShiftDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 shifts[]),
          (void)vr, (void)n, (void)shifts)
NO_CLOCKS(fmi3GetShiftFraction,
          (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[], fmi3UInt64 r[]),
          (void)vr, (void)n, (void)c, (void)r)
NO_CLOCKS(fmi3SetIntervalDecimal,
          (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 intervals[]),
          (void)vr, (void)n, (void)intervals)
NO_CLOCKS(fmi3SetIntervalFraction, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                    const fmi3UInt64 c[], const fmi3UInt64 r[]),
          (void)vr, (void)n, (void)c, (void)r)
NO_CLOCKS(fmi3SetShiftDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                const fmi3Float64 shifts[]),
          (void)vr, (void)n, (void)shifts)
NO_CLOCKS(fmi3SetShiftFraction,
          (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[], const fmi3UInt64 r[]),
          (void)vr, (void)n, (void)c, (void)r)

/* ------------------------------------------------------------------ events and Model Exchange */

FMI3_Export fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) { return instance ? fmi3OK : fmi3Error; }

FMI3_Export fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    if (!instance) return fmi3Error;
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = fmi3False;
    if (nextEventTime) *nextEventTime = 0.0;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) { return instance ? fmi3OK : fmi3Error; }

FMI3_Export fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!instance) return fmi3Error;
    if (enterEventMode) *enterEventMode = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    return fmi3OK;
}

FMI3_Export fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    return (fmi3Status)fi_set_time(FI(instance), time);
}

/* The continuous states (none for the steady-state tyre; fmi_common.h checks the count). */
FMI3_Export fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t nx)
{
    return (fmi3Status)fi_set_states(FI(instance), "fmi3SetContinuousStates", nx, x);
}
FMI3_Export fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t nx)
{
    return (fmi3Status)fi_get_derivatives(FI(instance), "fmi3GetContinuousStateDerivatives", nx, dx);
}
FMI3_Export fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 ei[], size_t ni)
{
    (void)ei;
    return instance && ni == 0 ? fmi3OK : fmi3Error;
}
FMI3_Export fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx)
{
    return (fmi3Status)fi_get_states(FI(instance), "fmi3GetContinuousStates", nx, x);
}
FMI3_Export fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 xn[], size_t nx)
{
    return (fmi3Status)fi_get_nominals(FI(instance), "fmi3GetNominalsOfContinuousStates", nx, xn);
}
FMI3_Export fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    if (!instance || !n) return fmi3Error;
    *n = 0;
    return fmi3OK;
}
FMI3_Export fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    if (!instance || !n) return fmi3Error;
    *n = fm_n_states();
    return fmi3OK;
}

/* ------------------------------------------------------------------ Co-Simulation */

FMI3_Export fmi3Status fmi3EnterStepMode(fmi3Instance instance) { return instance ? fmi3OK : fmi3Error; }

FMI3_Export fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                                  fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    fmi3Status status;
    (void)noSetFMUStatePriorToCurrentPoint;
    status = (fmi3Status)fi_do_step(FI(instance), "fmi3DoStep", currentCommunicationPoint, communicationStepSize);
    if (!instance) return status;
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = fm_time(INS->fi.model);
    return status;
}

#endif /* MF_FMU_UNITY */
