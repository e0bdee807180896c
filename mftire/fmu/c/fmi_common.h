/*
 * fmi_common.h -- what the FMI 2.0 and FMI 3.0 wrappers (fmi2_wrapper.c, fmi3_wrapper.c) do alike where the
 * standards leave it to the implementation: the instance's life-cycle states, the log categories and the
 * message formatting, the checks of the life-cycle, state and step calls.  Each wrapper keeps what its
 * standard's signatures and types force: the FMI functions themselves, memory, the importer's logger.
 *
 * A wrapper's instance starts with an FIInstance (its first member), so that the FMI instance pointer is an
 * FIInstance pointer (FI(c) below; NULL stays NULL).  Status codes are FM_OK / FM_WARNING / FM_ERROR of
 * fmu_model.h, equal to those of fmi2Status and fmi3Status.  Static functions of the FMU's one translation
 * unit (fmu.c).
 */
#ifndef FMI_COMMON_H
#define FMI_COMMON_H

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_model.h"

/* The life-cycle states of an instance (both standards). */
typedef enum { FI_INSTANTIATED, FI_INIT, FI_RUNNING, FI_TERMINATED, FI_ERROR } FIState;

typedef struct FIInstance FIInstance;

/* The wrapper's way to hand one finished message to the importer's logger. */
typedef void (*fi_emit_fn)(const FIInstance *fi, int status, const char *category, const char *message);

struct FIInstance {
    FMModel *model;               /* the model behind fmu_model.h */
    FIState state;
    int cosim;                    /* a Co-Simulation instance (else Model Exchange) */
    int log_errors, log_warnings; /* categories logStatusError / logStatusWarning on */
    fi_emit_fn emit;
};

/* The FIInstance at the start of a wrapper's instance c (NULL for NULL). */
#define FI(c) ((FIInstance *)(c))

/* Format and log through the importer's logger, unless the category is switched off (fi may be NULL). */
FM_FN void fi_logf(const FIInstance *fi, int status, const char *category, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    if (!fi || !fi->emit) return;
    if (status == FM_WARNING && !fi->log_warnings) return;
    if (status == FM_ERROR && !fi->log_errors) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fi->emit(fi, status, category, buf);
}

/* The model's logger (fm_log_fn of fmu_model.h; host: the FIInstance). */
FM_FN void fi_model_log(void *host, int status, const char *category, const char *message)
{
    fi_logf((const FIInstance *)host, status, category, "%s", message);
}

/* A refused call: the message logged as an error (fi may be NULL), FM_ERROR returned. */
FM_FN int fi_fail(const FIInstance *fi, const char *fmt, ...)
{
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fi_logf(fi, FM_ERROR, "logStatusError", "%s", buf);
    return FM_ERROR;
}

/* A new instance: instantiated, both log categories on, the model at its start values. */
FM_FN void fi_init(FIInstance *fi, FMModel *model, int cosim, fi_emit_fn emit)
{
    fi->model = model;
    fi->state = FI_INSTANTIATED;
    fi->cosim = cosim;
    fi->log_errors = fi->log_warnings = 1;
    fi->emit = emit;
    fm_init(model, fi_model_log, fi);
}

/* SetDebugLogging: no category switches both on; else logAll, logStatusWarning, logStatusError. */
FM_FN int fi_set_debug_logging(FIInstance *fi, int on, size_t n, const char *const categories[])
{
    size_t i;
    if (!fi) return FM_ERROR;
    if (n == 0) {
        fi->log_errors = fi->log_warnings = 1;
        return FM_OK;
    }
    if (!categories) return fi_fail(fi, "SetDebugLogging: NULL categories");
    for (i = 0; i < n; i++) {
        const char *cat = categories[i];
        if (!cat) continue;
        if (strcmp(cat, "logAll") == 0) fi->log_errors = fi->log_warnings = on ? 1 : 0;
        else if (strcmp(cat, "logStatusWarning") == 0) fi->log_warnings = on ? 1 : 0;
        else if (strcmp(cat, "logStatusError") == 0) fi->log_errors = on ? 1 : 0;
        else return fi_fail(fi, "unknown log category '%s'", cat);
    }
    return FM_OK;
}

/* A call in a state where the standard does not allow it: an error (the instance stays usable). */
FM_FN int fi_wrong_state(const FIInstance *fi, const char *fn)
{
    static const char *const names[] = {"instantiated", "initialization mode", "running", "terminated", "error"};
    return fi_fail(fi, "%s is not allowed in state '%s'", fn, names[fi->state]);
}

/* Whether fn may be called in state `state` (else logged: fi_wrong_state). */
FM_FN int fi_in_state(const FIInstance *fi, FIState state, const char *fn)
{
    if (!fi) return FM_ERROR;
    return fi->state == state ? FM_OK : fi_wrong_state(fi, fn);
}

FM_FN int fi_enter_initialization(FIInstance *fi, const char *fn)
{
    if (fi_in_state(fi, FI_INSTANTIATED, fn) != FM_OK) return FM_ERROR;
    fi->state = FI_INIT;
    return FM_OK;
}

/* ExitInitializationMode: the model checks its parameters and mode and evaluates (outputs are valid straight
 * after the initialisation); a refusal leaves the instance in the error state. */
FM_FN int fi_exit_initialization(FIInstance *fi, const char *fn)
{
    if (fi_in_state(fi, FI_INIT, fn) != FM_OK) return FM_ERROR;
    if (fm_exit_initialization(fi->model) != FM_OK) {
        fi->state = FI_ERROR;
        return FM_ERROR;
    }
    fi->state = FI_RUNNING;
    return FM_OK;
}

FM_FN int fi_terminate(FIInstance *fi)
{
    if (!fi) return FM_ERROR;
    fi->state = FI_TERMINATED;
    return FM_OK;
}

FM_FN int fi_reset(FIInstance *fi)
{
    if (!fi) return FM_ERROR;
    fm_reset(fi->model);
    fi->state = FI_INSTANTIATED;
    return FM_OK;
}

FM_FN int fi_set_time(FIInstance *fi, double t)
{
    if (!fi) return FM_ERROR;
    fm_set_time(fi->model, t);
    return FM_OK;
}

/* The calls on scalar variables (fn: the FMI function's name; vr: n value references, values: n values): each
 * value through the model's accessor (fmu_model.h), stopping at the first refusal.  A NULL instance, or NULL
 * arrays with n > 0, is an error.  Value references are 32-bit unsigned in both standards, Integer / Int32
 * values are int (the wrappers check the sizes). */
FM_FN int fi_arrays(const FIInstance *fi, const char *fn, size_t n, const void *vr, const void *values)
{
    if (!fi) return FM_ERROR;
    if (n > 0 && (!vr || !values)) return fi_fail(fi, "%s: NULL array argument", fn);
    return FM_OK;
}

/* What a call on scalar variables does with each value (fi_values). */
typedef enum { FI_GET_REAL, FI_SET_REAL, FI_GET_INT, FI_SET_INT } FIAccess;

/* values: double (Real) or int (Integer) values, read by the Set calls only. */
FM_FN int fi_values(FIInstance *fi, const char *fn, FIAccess access, const unsigned *vr, size_t n, void *values)
{
    size_t i;
    int rc;
    if (fi_arrays(fi, fn, n, vr, values) != FM_OK) return FM_ERROR;
    for (i = 0, rc = FM_OK; i < n && rc == FM_OK; i++)
        switch (access) {
        case FI_GET_REAL: rc = fm_get_real(fi->model, vr[i], (double *)values + i); break;
        case FI_SET_REAL: rc = fm_set_real(fi->model, vr[i], ((const double *)values)[i]); break;
        case FI_GET_INT: rc = fm_get_int(fi->model, vr[i], (int *)values + i); break;
        default: rc = fm_set_int(fi->model, vr[i], ((const int *)values)[i]); break;
        }
    return rc;
}

/* A call on the continuous states (fn: its name): nx must be the model's count, the array given if nx > 0. */
FM_FN int fi_states_call(const FIInstance *fi, const char *fn, size_t nx, const void *array)
{
    if (!fi) return FM_ERROR;
    if (nx != fm_n_states() || (nx > 0 && !array))
        return fi_fail(fi, "%s: %u continuous states, not %u", fn, fm_n_states(), (unsigned)nx);
    return FM_OK;
}

/* The calls on the continuous states (fn: the FMI function's name; array x of nx values). */
FM_FN int fi_set_states(FIInstance *fi, const char *fn, size_t nx, const double *x)
{
    if (fi_states_call(fi, fn, nx, x) != FM_OK) return FM_ERROR;
    return nx ? fm_set_states(fi->model, x) : FM_OK;
}

FM_FN int fi_get_states(FIInstance *fi, const char *fn, size_t nx, double *x)
{
    if (fi_states_call(fi, fn, nx, x) != FM_OK) return FM_ERROR;
    return nx ? fm_get_states(fi->model, x) : FM_OK;
}

FM_FN int fi_get_derivatives(FIInstance *fi, const char *fn, size_t nx, double *dx)
{
    if (fi_states_call(fi, fn, nx, dx) != FM_OK) return FM_ERROR;
    return nx ? fm_get_derivatives(fi->model, dx) : FM_OK;
}

FM_FN int fi_get_nominals(FIInstance *fi, const char *fn, size_t nx, double *xn)
{
    if (fi_states_call(fi, fn, nx, xn) != FM_OK) return FM_ERROR;
    if (nx) fm_get_nominals(xn);
    return FM_OK;
}

/* DoStep: a running Co-Simulation instance, a step size >= 0; the model advances from t by h. */
FM_FN int fi_do_step(FIInstance *fi, const char *fn, double t, double h)
{
    if (!fi) return FM_ERROR;
    if (!fi->cosim) return fi_fail(fi, "%s: not a Co-Simulation instance", fn);
    if (fi_in_state(fi, FI_RUNNING, fn) != FM_OK) return FM_ERROR;
    if (!(h >= 0.0)) return fi_fail(fi, "%s: invalid step size %g", fn, h);
    return fm_do_step(fi->model, t, h);
}

#endif /* FMI_COMMON_H */
