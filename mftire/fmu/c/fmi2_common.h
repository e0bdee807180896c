/*
 * fmi2_common.h -- what the two FMI 2.0 wrappers of mftire share (fmi2_common.c): the
 * instance header, logging through the importer's logger, and every FMI 2.0 function
 * that does not depend on the model (versions, debug logging, setup, the FMU-state,
 * event, status and input-derivative functions).
 *
 * A wrapper (fmi2_model.c: the steady-state tyre, fmi2_transient.c: the transient tyre)
 * puts an FMI2Base first in its instance struct, creates instances with fmi2_base_new,
 * points FMI2Base.time and FMI2Base.debug_logging at its model's fields, and implements
 * the model-specific functions (Instantiate, ExitInitializationMode, Reset, the value
 * access, the continuous states, DoStep).
 */
#ifndef FMI2_COMMON_H
#define FMI2_COMMON_H

#include <stddef.h>

#include "fmi2Functions.h"

typedef enum { FMI2_INSTANTIATED, FMI2_INIT, FMI2_RUNNING, FMI2_TERMINATED, FMI2_ERROR } FMI2State;

typedef struct {
    fmi2CallbackFunctions cb; /* the importer's callbacks (copied) */
    char *name;               /* instance name (allocated with cb.allocateMemory) */
    fmi2Type type;
    FMI2State state;
    int log_errors, log_warnings; /* categories logStatusError / logStatusWarning on */
    int *debug_logging;           /* the model's debug flag (category logAll) */
    double *time;                 /* the model's time */
} FMI2Base;

/* The FMI2Base of a component (it is the first member of every wrapper's instance). */
#define FMI2_BASE(c) ((FMI2Base *)(c))

/*
 * A zeroed instance of `size` bytes (the wrapper's struct, FMI2Base first) with the
 * callbacks, name and type filled in, or NULL (missing memory callbacks or wrong GUID:
 * logged through the importer's logger when there is one).
 */
FMI2Base *fmi2_base_new(size_t size, fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                        const char *expected_guid, const fmi2CallbackFunctions *functions);

/*
 * Log through the importer's logger, unless the category is switched off.  The message is
 * formatted here and passed as the format string with every '%' doubled, without variadic
 * arguments: a logger that formats (printf-style, as the standard asks) and a plain
 * callback that does not both show the same text.
 */
void fmi2_log(const FMI2Base *b, fmi2Status status, const char *category, const char *message);
void fmi2_logf(const FMI2Base *b, fmi2Status status, const char *category, const char *fmt, ...);

/* Log "<fn> is not supported" as an error and return fmi2Error. */
fmi2Status fmi2_unsupported(fmi2Component c, const char *fn);

/* Start of the value-access functions: a NULL component, or NULL arrays with n > 0, is an error. */
#define FMI2_CHECK_ARRAYS(c, n, a, b)                                                                            \
    do {                                                                                                         \
        if (!(c)) return fmi2Error;                                                                              \
        if ((n) > 0 && (!(a) || !(b))) {                                                                         \
            fmi2_logf(FMI2_BASE(c), fmi2Error, "logStatusError", "%s: NULL array argument", __func__);          \
            return fmi2Error;                                                                                    \
        }                                                                                                        \
    } while (0)

#endif /* FMI2_COMMON_H */
