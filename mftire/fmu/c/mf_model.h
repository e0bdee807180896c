/*
 * mf_model.h -- instance state shared by the FMI 2.0 and FMI 3.0 wrappers:
 * value-reference access, lazy evaluation and warnings through a logger.
 */
#ifndef MF_MODEL_H
#define MF_MODEL_H

#include "mf_eval.h"

/* Variable kinds of the generated value-reference table. */
enum { MF_K_TIME = 0, MF_K_INPUT, MF_K_OUTPUT, MF_K_MODE, MF_K_PARAM };

typedef struct {
    unsigned char kind;  /* MF_K_* */
    unsigned char fixed; /* parameter with variability "fixed" */
    unsigned short offset; /* byte offset in MFInputs / MFOutputs / MFParams */
} MFVarInfo;

/* Status codes: the same numbers as fmi2Status and fmi3Status. */
#define MF_STATUS_OK 0
#define MF_STATUS_WARNING 1
#define MF_STATUS_ERROR 3

/* How many times each kind of warning is logged before it is muted (unless debug logging is on). */
#define MF_WARN_REPEAT 10

/* Counters of the input/output guards (mf_model.c): 9 inputs, MF_MAX_DATA data inputs, the outputs. */
#define MF_GUARD_SLOTS (9 + MF_MAX_DATA + 1)

struct MFModel;
/* category: "logStatusWarning" / "logStatusError"; status: MF_STATUS_* */
typedef void (*mf_log_fn)(struct MFModel *model, int status, const char *category, const char *message);

typedef struct MFModel {
    MFParams params;
    MFInputs inputs;
    MFOutputs outputs;
    int use_mode;
    double time;
    int dirty;        /* inputs or parameters changed since the last evaluation */
    int initialized;  /* after ExitInitializationMode */
    int debug_logging;
    unsigned warn_count[MF_W_COUNT];
    unsigned guard_count[MF_GUARD_SLOTS]; /* input guards of mf_model.c (9 inputs, data, outputs) */
    mf_log_fn log;
    void *host;       /* the wrapper's own data (FMI callbacks) */
} MFModel;

void mf_model_init(MFModel *m, mf_log_fn log, void *host); /* start values */
void mf_model_reset(MFModel *m);                            /* back to start values */
int mf_model_validate(MFModel *m);                          /* FITTYP and useMode */
int mf_model_update(MFModel *m);                            /* evaluate if dirty */
int mf_model_get_real(MFModel *m, unsigned vr, double *value);
int mf_model_set_real(MFModel *m, unsigned vr, double value);
int mf_model_get_int(MFModel *m, unsigned vr, int *value);
int mf_model_set_int(MFModel *m, unsigned vr, int value);
void mf_model_logf(MFModel *m, int status, const char *category, const char *fmt, ...);
const char *mf_model_var_name(unsigned vr);
unsigned mf_model_n_vars(void);
const char *mf_model_guid(void);
int mf_model_is_output(unsigned vr);
unsigned mf_model_input_vrs(unsigned *vrs); /* fills vrs (if not NULL, room for 64) and returns the count */

#endif /* MF_MODEL_H */
