/*
 * fmu_common.h -- what both models behind fmu_model.h (mf_model.c, mt_model.c) do alike: log through the
 * wrapper's logger, rate-limit repeated warnings, refuse non-physical parameters.  Static functions of the
 * FMU's one translation unit (fmu.c).
 */
#ifndef FMU_COMMON_H
#define FMU_COMMON_H

#include <math.h>
#include <stdarg.h>
#include <stdio.h>

#include "fmu_model.h"
#include "mf_eval.h"

/* Format and log through the wrapper's logger (log may be NULL). */
FM_FN void fm_logf(fm_log_fn log, void *host, int status, const char *category, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    if (!log) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    log(host, status, category, buf);
}

/* A warning through the rate limit of fmu_model.h: logged when its slot is due at evaluation `evals`, with the
 * number of those not logged since the last message. */
FM_FN void fm_warn(fm_log_fn log, void *host, FMWarnSlot *slot, unsigned long evals, double time, const char *message)
{
    unsigned long skipped;
    if (!fm_warn_due(slot, evals, &skipped)) return;
    if (skipped)
        fm_logf(log, host, FM_WARNING, "logStatusWarning", "t=%.17g: %s (%lu more since the last message, not "
                "logged: one message per kind per %lu evaluations)", time, message, skipped, FM_WARN_EVERY);
    else
        fm_logf(log, host, FM_WARNING, "logStatusWarning", "t=%.17g: %s", time, message);
}

/* Whether the model refuses the value of the parameter at `slot` in p (writing why into msg): any non-finite
 * value, the bounds of mftire.mf.spec.PARAMETER_BOUNDS, a FITTYP that names no model family the evaluator
 * handles -- as the export refuses them in the file. */
FM_FN int fm_check_parameter(const MFParams *p, const double *slot, double value, char *msg, unsigned long n)
{
    static const MFParamBound bounds[] = MF_SPEC_PARAMETER_BOUNDS;
    unsigned k;
    int index = (int)(slot - (const double *)p);
    if (!isfinite(value)) {
        snprintf(msg, n, "%g: a parameter must be finite", value);
        return 1;
    }
    for (k = 0; k < sizeof bounds / sizeof bounds[0]; k++)
        if (bounds[k].index == index && (bounds[k].strict ? !(value > bounds[k].bound) : !(value >= bounds[k].bound))) {
            snprintf(msg, n, "%s = %g must be %s %g", bounds[k].name, value, bounds[k].strict ? ">" : ">=",
                     bounds[k].bound);
            return 1;
        }
    if (slot == &p->FITTYP) {
        MFParams trial = *p;
        trial.FITTYP = value;
        return mf_check_fittyp(&trial, msg, n) != MF_OK;
    }
    return 0;
}

#endif /* FMU_COMMON_H */
