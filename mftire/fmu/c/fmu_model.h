/*
 * fmu_model.h -- the one interface between the FMI wrappers and a model of mftire.
 *
 * The FMI 2.0 wrapper (fmi2_wrapper.c) and the FMI 3.0 wrapper (fmi3_wrapper.c) know nothing
 * of the tyre: they call these functions, which each model implements once (those every model does alike --
 * fm_init, fm_set_time, fm_time -- once for all in fmu_common.h):
 *   mf_model.c  the steady-state tyre (algebraic: no states), on mf_eval.c;
 *   mt_model.c  the transient tyre (two slip-deflection states), on mf_transient.c.
 * An FMU is one translation unit (fmu.c, generated at export): mf_eval.c, one model, one wrapper.
 * Every function here is static, so that only the FMI functions are external symbols (and take
 * FMI2_FUNCTION_PREFIX / FMI3_FUNCTION_PREFIX when the importer defines it: several tyres can be
 * linked statically into one executable).
 *
 * Status codes are those of fmi2Status / fmi3Status (FM_OK, FM_WARNING, FM_ERROR).
 */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stddef.h>

/* Every function of the interface is static (unused ones are no warning: a wrapper needs not call all). */
#if defined(__GNUC__) || defined(__clang__)
#define FM_FN static __attribute__((unused))
#else
#define FM_FN static
#endif

#define FM_OK 0
#define FM_WARNING 1
#define FM_ERROR 3

/* The model's instance (defined by the model file). */
typedef struct FMModel FMModel;

/* How the model logs: status FM_*, category "logStatusWarning" / "logStatusError". */
typedef void (*fm_log_fn)(void *host, int status, const char *category, const char *message);

/* Identity and sizes. */
FM_FN const char *fm_guid(void);          /* GUID (FMI 2) / instantiation token (FMI 3) */
FM_FN size_t fm_size(void);               /* bytes of an FMModel */
FM_FN unsigned fm_n_states(void);         /* continuous states (0: algebraic) */

/* Life cycle. */
FM_FN void fm_init(FMModel *m, fm_log_fn log, void *host); /* start values */
FM_FN void fm_reset(FMModel *m);                           /* back to the start values */
FM_FN int fm_exit_initialization(FMModel *m);             /* check parameters and mode, evaluate */
FM_FN void fm_set_time(FMModel *m, double t);
FM_FN double fm_time(const FMModel *m);

/* Variables (by value reference; the table is generated from the Python variable table). */
FM_FN int fm_get_real(FMModel *m, unsigned vr, double *value);
FM_FN int fm_set_real(FMModel *m, unsigned vr, double value);
FM_FN int fm_get_int(FMModel *m, unsigned vr, int *value);
FM_FN int fm_set_int(FMModel *m, unsigned vr, int value);
FM_FN int fm_is_unknown(unsigned vr);                        /* an output or a state derivative */
FM_FN unsigned fm_dependencies(unsigned *vrs, unsigned room); /* what every unknown depends on: the inputs,
                                                                  then the states; fills vrs (if not NULL,
                                                                  up to room) and returns the count */

/* Model Exchange (n = fm_n_states()). */
FM_FN int fm_get_states(FMModel *m, double *x);
FM_FN int fm_set_states(FMModel *m, const double *x);
FM_FN int fm_get_derivatives(FMModel *m, double *dx);
FM_FN void fm_get_nominals(double *xn);

/* Co-Simulation: advance from t by h with the inputs held. */
FM_FN int fm_do_step(FMModel *m, double t, double h);

/* ------------------------------------------------------------------ shared by the models */

/*
 * Repeated warnings: one message per kind per FM_WARN_EVERY evaluations, with the number not logged
 * since the last one -- whether or not the importer switched debug logging on (tools built on the
 * FMI Library always do).  An evaluation is one computation of the model at new inputs or states.
 */
#define FM_WARN_EVERY 1000UL

typedef struct {
    unsigned long next;       /* evaluation count from which the next message is logged */
    unsigned long suppressed; /* messages not logged since the last one */
} FMWarnSlot;

/* Whether a warning of slot s at evaluation `count` is logged now; *skipped: how many were not since. */
FM_FN int fm_warn_due(FMWarnSlot *s, unsigned long count, unsigned long *skipped)
{
    if (count >= s->next) {
        *skipped = s->suppressed;
        s->suppressed = 0;
        s->next = count + FM_WARN_EVERY;
        return 1;
    }
    s->suppressed++;
    return 0;
}

#endif /* FMU_MODEL_H */
