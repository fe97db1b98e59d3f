/* airframe: the attitude and rate dynamics of a generic small fixed-wing UAV as an FMI 2.0 co-simulation FMU,
 * the vehicle of silrig's FMU example (examples/fmu/README.md has the equations and the parameters).
 *
 * States: angle of attack and sideslip from trim (stability axes at the trimmed straight, level flight), the body
 * rates p, q, r, the Euler angles phi, theta, psi, and the positions of three first-order servos. The airspeed is
 * constant (no phugoid, no speed dynamics). Aerodynamics: linear stability derivatives; the rigid body, the
 * kinematics and gravity are nonlinear. Stevens & Lewis signs: a positive deflection of any surface makes a
 * negative moment. Each fmi2DoStep integrates over the communication step with RK4 in equal sub-steps of at most
 * 2.5 ms, the servo commands held over the step.
 *
 * Build: examples/fmu/build.sh examples/fmu/airframe airframe.fmu
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MODEL_NAME "airframe"
#define MODEL_STATE "an airframe state"
#define MODEL_GUID "{8c4e5a3b-2f61-4d0e-9b7a-a1f0e5c3d2b9}"
#define DEG (3.14159265358979323846 / 180.0)
#define GRAVITY_MPS2 9.80665
#define MAX_SUBSTEP_S 0.0025
#define TRAVEL_DEG 30.0 /* the inputs' min and max in modelDescription.xml: the servos stop there */

/* Value references, as in modelDescription.xml. */
enum {
    VR_AILERON = 0, VR_ELEVATOR, VR_RUDDER,                                    /* inputs, deg */
    VR_PHI = 10, VR_THETA, VR_PSI, VR_P, VR_Q, VR_R, VR_ALPHA, VR_BETA,        /* outputs */
    VR_AIRSPEED, VR_AILERON_POS, VR_ELEVATOR_POS, VR_RUDDER_POS, VR_OUTPUT_END, /* (VR_OUTPUT_END: one past) */
    VR_PARAM = 100 /* the parameters, in the order of struct parameters */
};

/* The parameters (causality parameter, variability fixed), each a double in this order from VR_PARAM on. */
typedef struct {
    double air_density_kgpm3, trim_airspeed_mps, mass_kg;
    double wing_area_m2, span_m, chord_m;
    double Jx_kgm2, Jy_kgm2, Jz_kgm2, Jxz_kgm2;
    double CL_alpha, CL_de, CY_beta, CY_dr;                   /* per rad */
    double Cl_beta, Cl_p, Cl_r, Cl_da, Cl_dr;                 /* per rad (rates made dimensionless by b/2V) */
    double Cm_alpha, Cm_q, Cm_de;                             /* per rad (q made dimensionless by c/2V) */
    double Cn_beta, Cn_p, Cn_r, Cn_da, Cn_dr;                 /* per rad */
    double servo_tau_s;
} parameters;
#define N_PARAMS ((int)(sizeof(parameters) / sizeof(double)))

static const parameters DEFAULTS = {
    1.225, 25.0, 12.0,              /* sea level, 25 m/s, 12 kg */
    0.6, 2.5, 0.25,                 /* wing */
    1.0, 1.3, 2.1, 0.1,             /* inertias */
    5.0, 0.3, -1.0, 0.15,           /* lift and side force */
    -0.05, -0.45, 0.12, -0.07, 0.003, /* rolling moment */
    -0.8, -14.0, -0.4,              /* pitching moment */
    0.06, -0.05, -0.12, 0.005, -0.035, /* yawing moment */
    0.04,                           /* servo time constant */
};

/* The state vector. */
enum { S_ALPHA, S_BETA, S_P, S_Q, S_R, S_PHI, S_THETA, S_PSI, S_DA, S_DE, S_DR, N_STATES };

/* Everything an FMU state holds: a plain struct, copied by value (no pointers), serialized as its bytes. */
typedef struct {
    double time;
    double x[N_STATES]; /* angles in rad, rates in rad/s, surfaces in rad */
    double u[3];        /* servo commands, deg, as set */
    parameters par;
    int mode;
    int reserved; /* 0: no padding of unknown bytes in a serialized state */
} snapshot;

#define STATE_MAGIC 0x46524941u /* "AIRF" */
#define STATE_VERSION 1u
/* ---- the model ---- */

static double clamp(double v, double lo, double hi) {
    return v < lo ? lo : v > hi ? hi : v;
}

/* dx/dt at state x with servo commands u (deg). */
static void derivatives(const parameters *k, const double *x, const double *u, double *dx) {
    const double V = k->trim_airspeed_mps;
    const double qbar = 0.5 * k->air_density_kgpm3 * V * V;
    const double qS = qbar * k->wing_area_m2;
    const double alpha = x[S_ALPHA], beta = x[S_BETA];
    const double p = x[S_P], q = x[S_Q], r = x[S_R];
    const double phi = x[S_PHI], theta = x[S_THETA];
    const double da = x[S_DA], de = x[S_DE], dr = x[S_DR];
    const double pn = p * k->span_m / (2.0 * V), rn = r * k->span_m / (2.0 * V), qn = q * k->chord_m / (2.0 * V);

    /* Aerodynamic forces (lift and side force beyond trim) and moments. */
    const double lift = qS * (k->CL_alpha * alpha + k->CL_de * de);
    const double side = qS * (k->CY_beta * beta + k->CY_dr * dr);
    const double L = qS * k->span_m * (k->Cl_beta * beta + k->Cl_p * pn + k->Cl_r * rn + k->Cl_da * da + k->Cl_dr * dr);
    const double M = qS * k->chord_m * (k->Cm_alpha * alpha + k->Cm_q * qn + k->Cm_de * de);
    const double N = qS * k->span_m * (k->Cn_beta * beta + k->Cn_p * pn + k->Cn_r * rn + k->Cn_da * da + k->Cn_dr * dr);

    /* Flight path: lift and gravity beyond the trimmed 1 g turn the velocity; the body turns under it. */
    const double g_V = GRAVITY_MPS2 / V;
    dx[S_ALPHA] = q - p * beta - lift / (k->mass_kg * V) + g_V * (cos(phi) * cos(theta) - 1.0);
    dx[S_BETA] = p * alpha - r + side / (k->mass_kg * V) + g_V * sin(phi) * cos(theta);

    /* Euler's equations with the product of inertia Jxz. */
    const double Jx = k->Jx_kgm2, Jy = k->Jy_kgm2, Jz = k->Jz_kgm2, Jxz = k->Jxz_kgm2;
    const double roll = L + (Jy - Jz) * q * r + Jxz * p * q;
    const double yaw = N + (Jx - Jy) * p * q - Jxz * q * r;
    const double det = Jx * Jz - Jxz * Jxz;
    dx[S_P] = (Jz * roll + Jxz * yaw) / det;
    dx[S_Q] = (M + (Jz - Jx) * p * r + Jxz * (r * r - p * p)) / Jy;
    dx[S_R] = (Jxz * roll + Jx * yaw) / det;

    /* Euler angle kinematics. */
    dx[S_PHI] = p + (q * sin(phi) + r * cos(phi)) * tan(theta);
    dx[S_THETA] = q * cos(phi) - r * sin(phi);
    dx[S_PSI] = (q * sin(phi) + r * cos(phi)) / cos(theta);

    /* First-order servos toward the command, which stops at the travel. */
    for (int c = 0; c < 3; c++) {
        dx[S_DA + c] = (clamp(u[c], -TRAVEL_DEG, TRAVEL_DEG) * DEG - x[S_DA + c]) / k->servo_tau_s;
    }
}

static void rk4(const parameters *k, double *x, const double *u, double h) {
    double k1[N_STATES], k2[N_STATES], k3[N_STATES], k4[N_STATES], y[N_STATES];
    derivatives(k, x, u, k1);
    for (int i = 0; i < N_STATES; i++) y[i] = x[i] + 0.5 * h * k1[i];
    derivatives(k, y, u, k2);
    for (int i = 0; i < N_STATES; i++) y[i] = x[i] + 0.5 * h * k2[i];
    derivatives(k, y, u, k3);
    for (int i = 0; i < N_STATES; i++) y[i] = x[i] + h * k3[i];
    derivatives(k, y, u, k4);
    for (int i = 0; i < N_STATES; i++) x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    for (int c = 0; c < 3; c++) {
        x[S_DA + c] = clamp(x[S_DA + c], -TRAVEL_DEG * DEG, TRAVEL_DEG * DEG);
    }
}

static double output(const snapshot *s, fmi2ValueReference vr) {
    switch (vr) {
    case VR_PHI: return s->x[S_PHI] / DEG;
    case VR_THETA: return s->x[S_THETA] / DEG;
    case VR_PSI: return s->x[S_PSI] / DEG;
    case VR_P: return s->x[S_P] / DEG;
    case VR_Q: return s->x[S_Q] / DEG;
    case VR_R: return s->x[S_R] / DEG;
    case VR_ALPHA: return s->x[S_ALPHA] / DEG;
    case VR_BETA: return s->x[S_BETA] / DEG;
    case VR_AIRSPEED: return s->par.trim_airspeed_mps;
    case VR_AILERON_POS: return s->x[S_DA] / DEG;
    case VR_ELEVATOR_POS: return s->x[S_DE] / DEG;
    default: return s->x[S_DR] / DEG; /* VR_RUDDER_POS */
    }
}

/* Each parameter must be finite; these must be positive too. */
static const char *invalid_parameter(const parameters *k) {
    const double *v = (const double *)k;
    static const char *const names[] = {"air_density_kgpm3", "trim_airspeed_mps", "mass_kg", "wing_area_m2", "span_m",
                                        "chord_m", "Jx_kgm2", "Jy_kgm2", "Jz_kgm2", "Jxz_kgm2", "CL_alpha", "CL_de",
                                        "CY_beta", "CY_dr", "Cl_beta", "Cl_p", "Cl_r", "Cl_da", "Cl_dr", "Cm_alpha",
                                        "Cm_q", "Cm_de", "Cn_beta", "Cn_p", "Cn_r", "Cn_da", "Cn_dr", "servo_tau_s"};
    for (int i = 0; i < N_PARAMS; i++) {
        if (!isfinite(v[i])) return names[i];
    }
    if (!(k->air_density_kgpm3 > 0) || !(k->trim_airspeed_mps > 0) || !(k->mass_kg > 0) || !(k->wing_area_m2 > 0) ||
        !(k->span_m > 0) || !(k->chord_m > 0) || !(k->Jx_kgm2 > 0) || !(k->Jy_kgm2 > 0) || !(k->Jz_kgm2 > 0) ||
        !(k->Jx_kgm2 * k->Jz_kgm2 > k->Jxz_kgm2 * k->Jxz_kgm2) || !(k->servo_tau_s > 0)) {
        return "a mass, length, area, density, airspeed, inertia (Jx*Jz > Jxz^2) or time constant that is not positive";
    }
    return NULL;
}

/* ---- FMI 2.0: the shared glue (examples/fmu/common/fmi2_glue.h), then what is this model's own ---- */

#include "fmi2_glue.h"

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    instance *m = c;
    if (m->s.mode != MODE_INITIALIZATION) {
        return fail(m, "fmi2ExitInitializationMode", "not in initialization mode");
    }
    const char *bad = invalid_parameter(&m->s.par);
    if (bad != NULL) {
        m->s.mode = MODE_ERROR;
        return fail(m, "fmi2ExitInitializationMode", "invalid parameter: %s", bad);
    }
    /* Trimmed straight and level: every state 0, the servos where they are commanded. */
    memset(m->s.x, 0, sizeof m->s.x);
    for (int c2 = 0; c2 < 3; c2++) {
        m->s.x[S_DA + c2] = clamp(m->s.u[c2], -TRAVEL_DEG, TRAVEL_DEG) * DEG;
    }
    m->s.mode = MODE_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] <= VR_RUDDER) {
            value[i] = m->s.u[vr[i]];
        } else if (vr[i] >= VR_PHI && vr[i] < VR_OUTPUT_END) {
            value[i] = output(&m->s, vr[i]);
        } else if (vr[i] >= VR_PARAM && vr[i] < VR_PARAM + (fmi2ValueReference)N_PARAMS) {
            value[i] = ((const double *)&m->s.par)[vr[i] - VR_PARAM];
        } else {
            return fail(m, "fmi2GetReal", "no Real variable has value reference %u", vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] <= VR_RUDDER) {
            m->s.u[vr[i]] = value[i];
        } else if (vr[i] >= VR_PARAM && vr[i] < VR_PARAM + (fmi2ValueReference)N_PARAMS) {
            if (m->s.mode != MODE_INSTANTIATED && m->s.mode != MODE_INITIALIZATION) {
                return fail(m, "fmi2SetReal", "parameter %u is fixed: set it before fmi2ExitInitializationMode",
                            vr[i]);
            }
            ((double *)&m->s.par)[vr[i] - VR_PARAM] = value[i];
        } else {
            return fail(m, "fmi2SetReal", "value reference %u is no input or parameter", vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    instance *m = c;
    if (m->s.mode != MODE_STEPPING) {
        return fail(m, "fmi2DoStep", "only after fmi2ExitInitializationMode (and before fmi2Terminate)");
    }
    if (!(communicationStepSize > 0) || !isfinite(communicationStepSize)) {
        return fail(m, "fmi2DoStep", "communication step size %g is not positive", communicationStepSize);
    }
    if (fabs(currentCommunicationPoint - m->s.time) > 1e-9 * fmax(1.0, fabs(m->s.time))) {
        return fail(m, "fmi2DoStep", "communication point %.17g is not the FMU's time %.17g", currentCommunicationPoint,
                    m->s.time);
    }
    int n = (int)ceil(communicationStepSize / MAX_SUBSTEP_S - 1e-9);
    const double h = communicationStepSize / n;
    for (int i = 0; i < n; i++) {
        rk4(&m->s.par, m->s.x, m->s.u, h);
    }
    for (int i = 0; i < N_STATES; i++) {
        if (!isfinite(m->s.x[i])) {
            m->s.mode = MODE_ERROR;
            return fail(m, "fmi2DoStep", "the state diverged at t = %g s", currentCommunicationPoint);
        }
    }
    m->s.time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}

/* Nothing of an airframe state to check past its header and its mode. */
static fmi2Status model_check_state(instance *m, const snapshot *s) {
    (void)m;
    (void)s;
    return fmi2OK;
}
