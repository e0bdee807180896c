/*
 * mf_model.h -- the value-reference table of the steady-state tyre FMU (mf_model.c), as
 * mf_model_gen.h (generated from mftire/fmu/variables.py) fills it.
 */
#ifndef MF_MODEL_H
#define MF_MODEL_H

#include "mf_eval.h"

/* Variable kinds of the generated value-reference table. */
enum { MF_K_TIME = 0, MF_K_INPUT, MF_K_OUTPUT, MF_K_MODE, MF_K_PARAM };

typedef struct {
    unsigned char kind;    /* MF_K_* */
    unsigned char fixed;   /* parameter with variability "fixed" */
    unsigned short offset; /* byte offset in MFInputs / MFOutputs / MFParams */
} MFVarInfo;

#endif /* MF_MODEL_H */
