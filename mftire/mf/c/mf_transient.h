/*
 * mf_transient.h -- transient (relaxation-length) tyre for the mftire transient FMU:
 * wheel kinematics in, contact-point slip deflections u, v as states, the
 * steady-state Magic Formula (mf_eval.c) evaluated at the transient slips.
 *
 * The equations are those of mftire/transient.py (Pacejka 2012 ch. 7, §7.2.1 contact-
 * point lag, §7.2.2 Magic Formula at the transient slips, §7.3 low-speed damping; MF 6.1
 * relaxation lengths, Besselink et al. 2010 eq 19).  The constants TR_* are members
 * of MFParams, generated from mftire.transient.CONSTANTS (one table for both).
 */
#ifndef MF_TRANSIENT_H
#define MF_TRANSIENT_H

#include "mf_eval.h"
#include "mt_config_gen.h" /* MT_THERMAL, MT_N_STATES, the data slots of the node temperatures (generated) */

#ifdef __cplusplus
extern "C" {
#endif

/* Kinematic inputs (mftire.transient.INPUTS), then the data variables of the model extensions. */
typedef struct {
    double Fz;      /* vertical load [N] */
    double Vx;      /* wheel-centre forward velocity, W axes [m/s] */
    double Vy;      /* wheel-centre lateral velocity, W axes, ISO y left [m/s] */
    double omega;   /* wheel spin [rad/s] */
    double gamma;   /* inclination [rad] */
    double P;       /* inflation pressure [Pa]; NaN or <= 0: INFLPRES */
    double muRoad;  /* road friction factor [-] */
    double yawRate; /* yaw rate for turn slip [rad/s] */
    double T_ambient; /* thermal block: ambient air temperature [degC] (unused without it) */
    double T_road;    /* thermal block: road surface temperature [degC] */
    double data[MF_MAX_DATA];
} MTInputs;

/* Input-only quantities of one operating point (computed once per input change). */
typedef struct {
    double Vx, Vsx, Vsy;  /* forward velocity, slip velocities [m/s] */
    double sigx, sigy;    /* relaxation lengths [m] */
    double slx, sly;      /* slips where the carcass deflection saturates: TR_SAT*F_slide/|K| (0: linear) [-] */
    double w;             /* low-speed weight: 1 at standstill, 0 from VXLOW */
    double My_sign;       /* smooth sign of the rolling-resistance moment */
    MFInputs ev;          /* evaluator inputs (slips set per evaluation) */
    MFOutputs zero;       /* steady state at zero slip: Re, sigma and the rolling offsets Fx, Fy, Mz */
    unsigned offsets;     /* MT_OFFSETS groups whose rolling offsets zero holds (all of them when w = 0) */
} MTKin;

/* The channel groups (MF_WANT_*) whose outputs carry a rolling offset that fades out below VXLOW. */
#define MT_OFFSETS (MF_WANT_FX | MF_WANT_FY | MF_WANT_MZ)

/* Transient outputs: the steady-state channels at the transient slips plus the slips. */
typedef struct {
    MFOutputs ss;  /* Fx, Fy, Mz, My corrected for the low-speed model */
    double kappa_t, alpha_t;
    double T_surface, T_bulk, T_gas, P_hot; /* thermal block: node temperatures [degC], the MF's pressure [Pa] */
    unsigned nonfinite; /* outputs of the last mt_outputs that were not finite and are set to 0 (to log) */
} MTOutputs;

/*
 * Kinematics: one steady-state evaluation at zero slip, of the groups it needs (mf_evaluate_unchecked): the
 * slip stiffnesses for the relaxation lengths (MF_WANT_RELAX; Re always) and, below VXLOW only (w > 0),
 * the rolling offsets of the groups `offsets` & MT_OFFSETS.  Offsets not computed are set to 0 (they are
 * multiplied by w = 0, or not used).  The evaluation does not check use_mode and FITTYP (mf_evaluate_unchecked):
 * the caller checks them when they are set (mf_check_mode, mf_check_fittyp).  The evaluator's warnings are
 * or-ed into *warnings (bit 1UL << kind of each MF_W_* kind; NULL: not reported).
 */
MF_API void mt_kinematics(const MFParams *p, int use_mode, const MTInputs *in, unsigned offsets, MTKin *k,
                          unsigned long *warnings);

/* State derivatives dx = (du/dt, dv/dt) at the state x = (u, v). */
MF_API void mt_rates(const MFParams *p, const MTKin *k, const double x[2], double dx[2]);

/*
 * Input guard, called before mt_kinematics: each non-finite input (NaN, +-Inf) of *in is replaced by its
 * last good value in *held (start values at instantiation), each finite input beyond its physical bound
 * (mftire.transient.INPUT_BOUNDS) is saturated to it; *held takes the values used.  Returns a bit mask
 * (bit i: input i in MTInputs order, MT_N_INPUTS of them) of the inputs replaced, for the wrapper to log.
 */
#define MT_N_INPUTS 8
/* Inputs the guard checks: the kinematic ones, then T_ambient, T_road of the thermal block. */
#define MT_N_GUARDED (MT_N_INPUTS + 2 * MT_THERMAL)
MF_API unsigned mt_guard_inputs(const MFParams *p, MTInputs *in, MTInputs *held);
MF_API const char *mt_input_name(unsigned i);

/*
 * Outputs at the state x: one steady-state evaluation at the transient slips, of the channel groups want
 * (MF_WANT_*; MF_WANT_ALL: every output).  The fields of groups not wanted are left untouched; kappa_t,
 * alpha_t, Fz and Re are always set.  A field that is not finite (known case: Mz, Mzr at Fz = 0 with turn
 * slip, where the Python evaluator gives NaN too) is set to 0 and counted in out->nonfinite.  k must hold the
 * offsets of want & MT_OFFSETS (mt_kinematics).  use_mode, FITTYP and *warnings as for mt_kinematics.
 */
MF_API void mt_outputs(const MFParams *p, int use_mode, const MTKin *k, const double x[2], unsigned want,
                       MTOutputs *out, unsigned long *warnings);

/* One exponential-Euler step of length h (rates and slope factors frozen at the start of the step):
 * stable for any h. */
MF_API void mt_step(const MFParams *p, const MTKin *k, double x[2], double h);

/* Advance the state by H with the inputs held (Co-Simulation step): one exact step mt_step(H) while it
 * stays linear (limiter inactive, slope factors within MT_CS_LINEAR_TOL), else ceil(H / TR_CS_STEP) equal
 * sub-steps of mt_step.  A non-finite result keeps the state. */
#define MT_CS_LINEAR_TOL 0.01
MF_API void mt_advance(const MFParams *p, const MTKin *k, double x[2], double H);

#if MT_THERMAL
/*
 * The thermal block (mftire.thermal.heat; states T = (T_s, T_b, T_g) [degC] after u, v; parameters TH_* of
 * [MFTIRE_THERMAL] as members of MFParams).  Each function is the Python function named, term for term.
 *
 * mt_thermal_inputs: the MF inputs the node temperatures drive, before mt_kinematics: the pressure *in->P is
 * the cold set pressure (NaN or <= 0: INFLPRES); with TH_PRESSURE != 0 it becomes the gas law's hot pressure
 * (heat.hot_pressure); the data slots of the laws that read a node get its temperature.  *P_hot: the
 * pressure the MF uses.
 */
MF_API void mt_thermal_inputs(const MFParams *p, const double T[3], MTInputs *in, double *P_hot);
/* Heat inputs q = (q_s, q_b, g_air) at the outputs o (MF_WANT_FX | MF_WANT_FY at least): TH_SLIP_SHARE times
 * heat.friction_power at the transient slips, simulation.bulk_power, heat.air_conductance. */
MF_API void mt_thermal_heat(const MFParams *p, const MTKin *k, const MTOutputs *o, double q[3]);
/* dT/dt = heat.node_rates. */
MF_API void mt_thermal_rates(const MFParams *p, const double q[3], double T_amb, double T_road, const double T[3],
                             double dT[3]);
/* One backward-Euler step of length h (heat.implicit_step): stable for any h.  A non-finite result keeps T. */
MF_API void mt_thermal_step(const MFParams *p, const double q[3], double T_amb, double T_road, double T[3], double h);
#endif

#ifdef __cplusplus
}
#endif
#endif /* MF_TRANSIENT_H */
