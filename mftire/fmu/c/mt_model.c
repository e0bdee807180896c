/*
 * mt_model.c -- the transient tyre behind the FMI wrappers (fmu_model.h): two continuous states
 * u, v (the contact-point slip deflections) with their derivatives, on mf_transient.c.
 *
 * Model Exchange: fm_get_derivatives returns (du/dt, dv/dt) of mftire/transient.py.
 * Co-Simulation: fm_do_step holds the inputs over the communication step H and advances the
 * states with mt_advance (mf_transient.c: the integration is the model's, not the wrapper's).
 *
 * Thermal block (MT_THERMAL, a .tir with [MFTIRE_THERMAL]): three more states, the node temperatures
 * x[2..4] = (T_s, T_b, T_g) [degC], which drive the MF's pressure and the laws that read a node
 * (mt_thermal_inputs, so the kinematics depend on them); their derivatives are heat.node_rates at the heat
 * of the outputs (ME).  Co-Simulation: the temperatures the laws and the pressure read are held over a step
 * like the inputs; the slip states advance first, then the temperatures by one backward-Euler step
 * (mt_thermal_step) with the heat of the forces at the end of the slip step, which are the outputs the host
 * reads after the step (two Magic Formula evaluations per step, as without the block; the node-temperature
 * outputs are the new states).  Initial temperatures: the parameters TH_T_INIT_*.
 *
 * Outputs are computed lazily: the first read of an output after new inputs, states or a step
 * evaluates the Magic Formula at the transient slips for the channel groups (MF_WANT_* of mf_eval.h)
 * of every output read so far (FMVarInfo.want), and the zero-slip evaluation of the kinematics computes
 * the rolling offsets only below VXLOW and only for those groups.  Each output equals the full
 * evaluation (mt_outputs with MF_WANT_ALL) bit for bit; a group read for the first time is added
 * (one more evaluation then).  An input set to its present value (bit for bit) changes nothing.
 *
 * The value-reference table, start values and GUID come from mt_model_gen.h, generated
 * by mftire/fmu/transient_export.py from one variable table.
 */
#ifdef MF_FMU_UNITY /* a part of fmu.c (alone, for an importer that compiles every .c: nothing) */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "fmu_common.h"
#include "mf_transient.h"
#include "mt_model_gen.h"

/* The value-reference table (fmu_common.h). */
static const FMVarTable TABLE = {MT_VARS, MT_VAR_NAMES, MT_N_VARS};

/* The input guard of the transient model (mt_guard_inputs of mf_transient.c: non-finite inputs hold their last
 * good value, inputs beyond their physical bounds are saturated), where the model provides it. */
#if defined(MT_N_INPUTS)
#define MT_HAS_GUARD 1
#else
#define MT_HAS_GUARD 0
#endif

struct FMModel {
    FMBase b; /* first: what every model keeps (fmu_common.h); b.evals counts output and derivative evaluations */
    MFParams params;
    MTInputs inputs;
#if MT_HAS_GUARD
    MTInputs held;                  /* last good inputs (mt_guard_inputs) */
    FMWarnSlot guard[MT_N_GUARDED]; /* the guard's warnings, per input */
    FMWarnSlot nonfinite;           /* outputs set to 0 by mt_outputs */
#endif
    double x[MT_N_STATES];
#if MT_THERMAL
    double P_hot;          /* the pressure the MF uses (mt_thermal_inputs) */
    double T_amb, T_road;  /* the guarded thermal inputs of the kinematics */
    int T_moved;           /* a Co-Simulation step moved the temperatures since the kinematics */
#endif
    MTKin kin;
    MTOutputs out;
    int kin_ok, out_ok;
    unsigned out_have; /* channel groups of out (valid when out_ok) */
    unsigned out_want; /* channel groups of every output read so far */
};

static const char *fm_guid(void) { return MT_GUID; }
static size_t fm_size(void) { return sizeof(FMModel); }
static unsigned fm_n_states(void) { return MT_N_STATES; }
static int fm_is_unknown(unsigned vr) { return fm_var_is_unknown(&TABLE, vr); }
static unsigned fm_dependencies(unsigned *vrs, unsigned room) { return fm_var_dependencies(&TABLE, vrs, room); }

static void fm_reset(FMModel *m)
{
    m->params = MT_PARAM_START;
    m->inputs = MT_INPUT_START;
#if MT_HAS_GUARD
    m->held = MT_INPUT_START;
    memset(m->guard, 0, sizeof m->guard);
    memset(&m->nonfinite, 0, sizeof m->nonfinite);
#endif
    {
        unsigned i;
        for (i = 0; i < MT_N_STATES; i++) m->x[i] = MT_STATE_START[i];
    }
    fm_base_reset(&m->b, MT_USEMODE_START);
    m->kin_ok = m->out_ok = 0;
    m->out_have = m->out_want = 0;
}

/* The evaluator's warnings `kinds` (MF_W_* bits) through the rate limit, but MFeval's low-speed mode: the
 * transient model replaces it. */
static void warn_kinds(FMModel *m, unsigned long kinds)
{
    fm_base_warn_kinds(&m->b, &m->params, kinds & ~(1UL << MF_W_LOW_SPEED));
}

/* The kinematics, with the rolling offsets of the output groups read so far.  useMode and FITTYP are checked when
 * they are set (fm_set_mode, fm_set_parameter_ok) and their start values at export, so the evaluations do not
 * check them (mt_kinematics, mt_outputs). */
static void update_kin(FMModel *m)
{
    unsigned long kinds = 0;
    MTInputs in;
    if (m->kin_ok && !(m->out_want & MT_OFFSETS & ~m->kin.offsets)) return;
    in = m->inputs;
#if MT_HAS_GUARD
    {
        unsigned i, bad = mt_guard_inputs(&m->params, &in, &m->held); /* the model's guard, before the states */
        char text[160];
        for (i = 0; i < MT_N_GUARDED; i++)
            if (bad & (1u << i)) {
                snprintf(text, sizeof text, "input '%s' not finite or out of range: the last good value or the "
                         "bound is used", mt_input_name(i));
                fm_base_warn(&m->b, &m->guard[i], text);
            }
    }
#endif
#if MT_THERMAL
    m->T_moved = 0;
    m->T_amb = in.T_ambient;
    m->T_road = in.T_road;
    mt_thermal_inputs(&m->params, &m->x[2], &in, &m->P_hot); /* the hot pressure and the laws' node temperatures */
#endif
    mt_kinematics(&m->params, m->b.use_mode, &in, m->out_want, &m->kin, &kinds);
    warn_kinds(m, kinds);
    m->kin_ok = 1;
}

/* The outputs of the channel groups `want` (and of all groups read before). */
static void update_out(FMModel *m, unsigned want)
{
    unsigned long kinds = 0;
    m->out_want |= want;
    if (m->out_ok && !(m->out_want & ~m->out_have)) return;
    m->b.evals++; /* the clock of the warning rate limit: output evaluations and derivative evaluations */
    update_kin(m);
    mt_outputs(&m->params, m->b.use_mode, &m->kin, m->x, m->out_want, &m->out, &kinds);
    warn_kinds(m, kinds);
#if MT_HAS_GUARD
    if (m->out.nonfinite) {
        char text[96];
        snprintf(text, sizeof text, "%u output(s) not finite, set to 0", m->out.nonfinite);
        fm_base_warn(&m->b, &m->nonfinite, text);
    }
#endif
#if MT_THERMAL
    m->out.T_surface = m->x[2];
    m->out.T_bulk = m->x[3];
    m->out.T_gas = m->x[4];
    m->out.P_hot = m->P_hot;
#endif
    m->out_have = m->out_want;
    m->out_ok = 1;
}

/* Every state derivative at the present inputs and states (dx: MT_N_STATES values). */
static void derivatives(FMModel *m, double *dx)
{
    update_kin(m);
    mt_rates(&m->params, &m->kin, m->x, dx);
#if MT_THERMAL
    {
        double q[3];
        update_out(m, MF_WANT_FX | MF_WANT_FY); /* the heat of the forces at the transient slips */
        mt_thermal_heat(&m->params, &m->kin, &m->out, q);
        mt_thermal_rates(&m->params, q, m->T_amb, m->T_road, &m->x[2], &dx[2]);
    }
#endif
}

/* Store an input or parameter; the kinematics and outputs are out of date unless the value is the same. */
static void store(FMModel *m, double *dst, double value)
{
    if (memcmp(dst, &value, sizeof value) == 0) return; /* bit for bit the same: nothing changes */
    *dst = value;
    m->kin_ok = m->out_ok = 0;
}

/* Thermal block: whether the parameter at value reference vr refuses `value` (the bounds of [MFTIRE_THERMAL],
 * mftire.mf.thermal_section.bounds, generated into mt_model_gen.h); the refusal is logged.  0 without the block. */
static int thermal_param_error(FMModel *m, unsigned vr, double value)
{
#if MT_THERMAL
    static const MTThermalBound bounds[] = MT_THERMAL_BOUNDS;
    unsigned k;
    for (k = 0; k < sizeof bounds / sizeof bounds[0]; k++)
        if (bounds[k].offset == MT_VARS[vr].offset && MT_VARS[vr].kind == FM_K_PARAM && isfinite(value) &&
            (bounds[k].kind == 0 ? !(value > bounds[k].bound)
                                 : bounds[k].kind == 1 ? !(value >= bounds[k].bound) : !(value == 0.0 || value == 1.0))) {
            logf_(m, FM_ERROR, "logStatusError", "%s = %g must be %s", MT_VAR_NAMES[vr], value, bounds[k].text);
            return 1;
        }
#else
    (void)m, (void)vr, (void)value;
#endif
    return 0;
}

/* The parameters are checked by fm_check_initialization (the bounds of mftire.mf.spec, VXLOW > 0, TR_SAT >= 0
 * and TR_CS_STEP > 0 among them), then by thermal_param_error. */
static int fm_exit_initialization(FMModel *m)
{
    if (fm_check_initialization(m->b.log, m->b.host, &m->params, m->b.use_mode, &TABLE) != FM_OK) return FM_ERROR;
    {
        unsigned vr; /* the bounds of [MFTIRE_THERMAL] (thermal block) */
        for (vr = 0; vr < MT_N_VARS; vr++)
            if (MT_VARS[vr].kind == FM_K_PARAM && thermal_param_error(m, vr, *fm_slot(&m->params, &MT_VARS[vr])))
                return FM_ERROR;
    }
    update_out(m, 0);
    m->b.initialized = 1;
    return FM_OK;
}

static int fm_get_real(FMModel *m, unsigned vr, double *value)
{
    const FMVarInfo *v = fm_var(&TABLE, vr);
    double dx[MT_N_STATES];
    if (!v) return fm_not_a(m->b.log, m->b.host, vr, "Real");
    if (fm_get_known(v, m->b.time, &m->inputs, &m->params, value)) return FM_OK;
    switch (v->kind) {
    case FM_K_STATE: *value = m->x[v->offset]; return FM_OK;
    case FM_K_DER:
        derivatives(m, dx);
        *value = dx[v->offset];
        return FM_OK;
    case FM_K_OUTPUT:
        update_out(m, v->want);
        *value = *fm_slot(&m->out, v);
        return FM_OK;
    default: return fm_not_a(m->b.log, m->b.host, vr, "Real");
    }
}

static int fm_set_real(FMModel *m, unsigned vr, double value)
{
    const FMVarInfo *v = fm_var(&TABLE, vr);
    if (!v) return fm_not_a(m->b.log, m->b.host, vr, "Real");
    switch (v->kind) {
    case FM_K_INPUT:
        store(m, fm_slot(&m->inputs, v), value);
        return FM_OK;
    case FM_K_PARAM:
        if (fm_set_parameter_ok(m->b.log, m->b.host, &TABLE, &m->params, vr, value, m->b.initialized) != FM_OK)
            return FM_ERROR;
        if (thermal_param_error(m, vr, value)) return FM_ERROR;
        store(m, fm_slot(&m->params, v), value);
#if MT_THERMAL
        { /* an initial temperature sets its state (the parameters are fixed: before initialisation only) */
            static const size_t init[3] = {offsetof(MFParams, TH_T_INIT_SURFACE), offsetof(MFParams, TH_T_INIT_BULK),
                                           offsetof(MFParams, TH_T_INIT_GAS)};
            unsigned i;
            for (i = 0; i < 3; i++)
                if (v->offset == init[i]) m->x[2 + i] = value;
        }
#endif
        return FM_OK;
    case FM_K_STATE:
        if (m->b.initialized) {
            logf_(m, FM_ERROR, "logStatusError", "%s: set states with fmi2SetContinuousStates / "
                  "fmi3SetContinuousStates", MT_VAR_NAMES[vr]);
            return FM_ERROR;
        }
        m->x[v->offset] = value;
        m->out_ok = 0;
        if (v->offset >= 2) m->kin_ok = 0; /* node temperatures drive the kinematics */
        return FM_OK;
    default:
        logf_(m, FM_ERROR, "logStatusError", "%s cannot be set", MT_VAR_NAMES[vr]);
        return FM_ERROR;
    }
}

static int fm_get_int(FMModel *m, unsigned vr, int *value)
{
    return fm_get_mode(m->b.log, m->b.host, vr, MT_VR_USEMODE, m->b.use_mode, value);
}

static int fm_set_int(FMModel *m, unsigned vr, int value)
{
    if (fm_set_mode(m->b.log, m->b.host, vr, MT_VR_USEMODE, value, &m->b.use_mode) != FM_OK) return FM_ERROR;
    m->kin_ok = m->out_ok = 0;
    return FM_OK;
}

/* ------------------------------------------------------------------ Model Exchange */

static int fm_set_states(FMModel *m, const double *x)
{
    unsigned i;
    for (i = 0; i < MT_N_STATES; i++) m->x[i] = x[i];
    m->out_ok = 0;
    if (MT_THERMAL) m->kin_ok = 0; /* node temperatures drive the kinematics */
    return FM_OK;
}

static int fm_get_states(FMModel *m, double *x)
{
    unsigned i;
    for (i = 0; i < MT_N_STATES; i++) x[i] = m->x[i];
    return FM_OK;
}

static int fm_get_derivatives(FMModel *m, double *dx)
{
    m->b.evals++;
    derivatives(m, dx);
    return FM_OK;
}

static void fm_get_nominals(double *xn)
{
    unsigned i;
    xn[0] = xn[1] = 1e-3; /* deflections of the order of a millimetre */
    for (i = 2; i < MT_N_STATES; i++) xn[i] = 100.0; /* temperatures of the order of 100 degC */
}

/* ------------------------------------------------------------------ Co-Simulation */

static int fm_do_step(FMModel *m, double t, double h)
{
#if MT_THERMAL
    if (m->T_moved) m->kin_ok = 0; /* the kinematics of the present temperatures */
#endif
    update_kin(m); /* inputs (and node temperatures) are held over the step */
    mt_advance(&m->params, &m->kin, m->x, h);
    m->b.time = t + h;
    m->out_ok = 0; /* the outputs at the new state are computed when read */
#if MT_THERMAL
    if (h > 0.0) {
        double q[3];
        update_out(m, MF_WANT_FX | MF_WANT_FY); /* the forces at the end of the slip step */
        mt_thermal_heat(&m->params, &m->kin, &m->out, q);
        mt_thermal_step(&m->params, q, m->T_amb, m->T_road, &m->x[2], h);
        m->out.T_surface = m->x[2]; /* the new states; the other outputs read the temperatures held */
        m->out.T_bulk = m->x[3];
        m->out.T_gas = m->x[4];
        m->T_moved = 1;
    }
#endif
    return FM_OK;
}

#endif /* MF_FMU_UNITY */
