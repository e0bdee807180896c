/*
 * mt_probe.c -- a test and benchmark harness of the transient C model (mftire.fmu.transient_export.
 * build_probe_library): the model functions of mf_transient.c with default visibility, without any FMI
 * function.  Compiled with mf_eval.c and mf_transient.c (not part of an FMU).
 */
#include <string.h>
#include <time.h>
#include "fmu_common.h"
#include "mf_transient.h"
#include "mt_model_gen.h"

static void load_inputs(MTInputs *in, const double *inputs)
{
    memset(in, 0, sizeof *in);
    in->Fz = inputs[0]; in->Vx = inputs[1]; in->Vy = inputs[2]; in->omega = inputs[3];
    in->gamma = inputs[4]; in->P = inputs[5]; in->muRoad = inputs[6]; in->yawRate = inputs[7];
}

/* MF_OK, or the code of a use_mode or FITTYP the evaluator refuses (the evaluations do not check them). */
static int checked(int use_mode)
{
    char msg[8];
    if (mf_check_mode(use_mode, msg, sizeof msg) != MF_OK) return MF_BAD_MODE;
    return mf_check_fittyp(&MT_PARAM_START, msg, sizeof msg) != MF_OK ? MF_BAD_FITTYP : MF_OK;
}

/* The kinematics and every output (all channel groups) at the inputs in and the state x. */
static int evaluate_all(int use_mode, const MTInputs *in, const double *x, MTKin *k, MTOutputs *o)
{
    int rc = checked(use_mode);
    if (rc) return rc;
    mt_kinematics(&MT_PARAM_START, use_mode, in, MF_WANT_ALL, k, NULL);
    mt_outputs(&MT_PARAM_START, use_mode, k, x, MF_WANT_ALL, o, NULL);
    return 0;
}

/* The outputs Fx, Fy, Mz, Mx, My, kappa_t, alpha_t into y. */
static void copy_forces(const MTOutputs *o, double *y)
{
    y[0] = o->ss.Fx; y[1] = o->ss.Fy; y[2] = o->ss.Mz; y[3] = o->ss.Mx; y[4] = o->ss.My;
    y[5] = o->kappa_t; y[6] = o->alpha_t;
}

/* Seconds per call of n calls timed from t0 (the benchmarks). */
static double seconds_per_call(const struct timespec *t0, long n)
{
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return ((double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec)) / (double)n;
}

/* params: NULL = start values; inputs: the 8 kinematic inputs; x: 2 states. */
__attribute__((visibility("default"))) int mt_probe_rates(int use_mode, const double *inputs, const double *x,
                                                          double *dx, double *kin)
{
    MTInputs in;
    MTKin k;
    int rc;
    load_inputs(&in, inputs);
    if ((rc = checked(use_mode)) != 0) return rc;
    mt_kinematics(&MT_PARAM_START, use_mode, &in, 0u, &k, NULL);
    mt_rates(&MT_PARAM_START, &k, x, dx);
    if (kin) { kin[0] = k.Vsx; kin[1] = k.Vsy; kin[2] = k.sigx; kin[3] = k.sigy; kin[4] = k.w; }
    return 0;
}

/* Every output at the 8 kinematic inputs and the state x, from the full evaluation (all channel groups). */
static int outputs_at(int use_mode, const double *inputs, const double *x, MTOutputs *o)
{
    MTInputs in;
    MTKin k;
    load_inputs(&in, inputs);
    return evaluate_all(use_mode, &in, x, &k, o);
}

/* Outputs (Fx, Fy, Mz, Mx, My, kappa_t, alpha_t) at the state x. */
__attribute__((visibility("default"))) int mt_probe_outputs(int use_mode, const double *inputs, const double *x,
                                                            double *y)
{
    MTOutputs o;
    int rc = outputs_at(use_mode, inputs, x, &o);
    if (rc == 0) copy_forces(&o, y);
    return rc;
}

/* Every output (value-reference order) at the state x, from the full evaluation (all channel groups). */
__attribute__((visibility("default"))) int mt_probe_all_outputs(int use_mode, const double *inputs, const double *x,
                                                                double *y)
{
    MTOutputs o;
    int vr, i = 0, rc = outputs_at(use_mode, inputs, x, &o);
    if (rc) return rc;
    for (vr = 0; vr < MT_N_VARS; vr++)
        if (MT_VARS[vr].kind == FM_K_OUTPUT) y[i++] = *fm_slot(&o, &MT_VARS[vr]);
    return 0;
}

/* Seconds per Model Exchange derivative evaluation (kinematics + rates), timed in C over n calls
 * with the inputs changing every call (as between two solver calls). */
__attribute__((visibility("default"))) double mt_probe_bench(int use_mode, const double *inputs, long n)
{
    MTInputs in;
    MTKin k;
    double x[2] = {1e-3, -2e-3}, dx[2], acc = 0.0;
    struct timespec t0;
    long i;
    if (checked(use_mode)) return -1.0;
    load_inputs(&in, inputs);
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (i = 0; i < n; i++) {
        in.Vy = inputs[2] + 1e-9 * (double)(i & 1023);
        mt_kinematics(&MT_PARAM_START, use_mode, &in, 0u, &k, NULL);
        mt_rates(&MT_PARAM_START, &k, x, dx);
        acc += dx[0] + dx[1];
    }
    if (acc != acc) return -1.0;
    return seconds_per_call(&t0, n);
}

#if MT_THERMAL
/* Thermal block at the inputs (the 8 kinematic ones, T_ambient, T_road) and the state x (u, v, T_s, T_b, T_g):
 * every derivative dx (5), the heat q = (q_s, q_b, g_air), P_hot, the outputs y (Fx, Fy, Mz, Mx, My, kappa_t,
 * alpha_t) and the node temperatures Tn after one backward-Euler step of h with that heat. */
__attribute__((visibility("default"))) int mt_probe_thermal(int use_mode, const double *inputs, const double *x,
                                                            double h, double *dx, double *q, double *P_hot,
                                                            double *y, double *Tn)
{
    MTInputs in;
    MTKin k;
    MTOutputs o;
    int rc;
    load_inputs(&in, inputs);
    in.T_ambient = inputs[8];
    in.T_road = inputs[9];
    mt_thermal_inputs(&MT_PARAM_START, &x[2], &in, P_hot);
    if ((rc = evaluate_all(use_mode, &in, x, &k, &o)) != 0) return rc;
    mt_rates(&MT_PARAM_START, &k, x, dx);
    mt_thermal_heat(&MT_PARAM_START, &k, &o, q);
    mt_thermal_rates(&MT_PARAM_START, q, in.T_ambient, in.T_road, &x[2], &dx[2]);
    copy_forces(&o, y);
    Tn[0] = x[2]; Tn[1] = x[3]; Tn[2] = x[4];
    mt_thermal_step(&MT_PARAM_START, q, in.T_ambient, in.T_road, Tn, h);
    return 0;
}
#endif

#if MT_THERMAL
/* Seconds per Model Exchange derivative evaluation of the thermal block (the node temperatures into the
 * inputs, kinematics, slip rates, the forces at the transient slips, the heat, the node rates), timed in C
 * over n calls with the inputs changing every call. */
__attribute__((visibility("default"))) double mt_probe_bench_thermal(int use_mode, const double *inputs, long n)
{
    MTInputs in0, in;
    MTKin k;
    MTOutputs o;
    double x[5] = {1e-3, -2e-3, 60.0, 50.0, 40.0}, dx[5], q[3], P_hot, acc = 0.0;
    struct timespec t0;
    long i;
    if (checked(use_mode)) return -1.0;
    load_inputs(&in0, inputs);
    in0.T_ambient = 20.0;
    in0.T_road = 30.0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    for (i = 0; i < n; i++) {
        in = in0;
        in.Vy = inputs[2] + 1e-9 * (double)(i & 1023);
        mt_thermal_inputs(&MT_PARAM_START, &x[2], &in, &P_hot);
        mt_kinematics(&MT_PARAM_START, use_mode, &in, 0u, &k, NULL);
        mt_rates(&MT_PARAM_START, &k, x, dx);
        mt_outputs(&MT_PARAM_START, use_mode, &k, x, MF_WANT_FX | MF_WANT_FY, &o, NULL);
        mt_thermal_heat(&MT_PARAM_START, &k, &o, q);
        mt_thermal_rates(&MT_PARAM_START, q, in.T_ambient, in.T_road, &x[2], &dx[2]);
        acc += dx[0] + dx[1] + dx[2];
    }
    if (acc != acc) return -1.0;
    return seconds_per_call(&t0, n);
}
#endif
