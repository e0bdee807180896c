/*
 * fmi2_model.c -- FMI 2.0 Model Exchange and Co-Simulation wrapper of the mftire
 * Magic Formula evaluator (mf_eval.c).  The tyre is algebraic: no continuous
 * states, no event indicators; every output depends directly on every input.
 *
 * Uses the FMI 2.0 standard headers (fmi2Functions.h and friends); the functions that do
 * not depend on the model are in fmi2_common.c, shared with the transient tyre.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2_common.h"
#include "mf_model.h"

typedef struct {
    FMI2Base base; /* first: fmi2_common.c sees the instance as an FMI2Base */
    MFModel model;
} Instance;

static void log_cb(MFModel *m, int status, const char *category, const char *message)
{
    fmi2_log((const FMI2Base *)m->host, (fmi2Status)status, category, message);
}

#define INS ((Instance *)c)

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                                          fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Instance *ins;
    (void)fmuResourceLocation;
    (void)visible;
    ins = (Instance *)fmi2_base_new(sizeof(Instance), instanceName, fmuType, fmuGUID, mf_model_guid(), functions);
    if (!ins) return NULL;
    mf_model_init(&ins->model, log_cb, ins);
    ins->model.debug_logging = loggingOn ? 1 : 0;
    ins->base.debug_logging = &ins->model.debug_logging;
    ins->base.time = &ins->model.time;
    return ins;
}

FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    if (!c) return fmi2Error;
    /* outputs are valid straight after initialisation */
    if (mf_model_validate(&INS->model) != MF_STATUS_OK || mf_model_update(&INS->model) != MF_STATUS_OK) {
        INS->base.state = FMI2_ERROR;
        return fmi2Error;
    }
    INS->model.initialized = 1;
    INS->base.state = FMI2_RUNNING;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c)
{
    if (!c) return fmi2Error;
    mf_model_reset(&INS->model);
    INS->base.state = FMI2_INSTANTIATED;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (mf_model_get_real(&INS->model, vr[i], &value[i]) != MF_STATUS_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++) {
        int v;
        if (mf_model_get_int(&INS->model, vr[i], &v) != MF_STATUS_OK) return fmi2Error;
        value[i] = v;
    }
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (mf_model_set_real(&INS->model, vr[i], value[i]) != MF_STATUS_OK) return fmi2Error;
    return fmi2OK;
}

FMI2_Export fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                      const fmi2Integer value[])
{
    size_t i;
    FMI2_CHECK_ARRAYS(c, n, vr, value);
    for (i = 0; i < n; i++)
        if (mf_model_set_int(&INS->model, vr[i], value[i]) != MF_STATUS_OK) return fmi2Error;
    return fmi2OK;
}

/* ------------------------------------------------------------------ Model Exchange: no continuous states */

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
