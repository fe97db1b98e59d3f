/* attitude: a "foreign" three-axis attitude vehicle as an FMI 2.0 co-simulation FMU, written the way a tool outside
 * silrig would write one (no silrig annotation, inputs named with their unit, no output reporting a surface's
 * position, a dimensionless throttle): the fixture of silrig's tests for what the rig prints, draws and judges of a
 * plant that is not the F-16.
 *
 * The model is a rigid body whose body rates are driven by the surface deflections with linear damping:
 *   p' = -roll_damping_per_s * p - aileron_dps2_per_deg * aileron_deg
 *   q' = -pitch_damping_per_s * q - elevator_dps2_per_deg * elevator_deg + throttle_dps2 * (throttle - 0.5)
 *   r' = -yaw_damping_per_s * r - rudder_dps2_per_deg * rudder_deg
 * (Stevens & Lewis signs: a positive deflection makes a negative moment; throttle above one half pitches up) and
 * the Euler angles phi, theta, psi follow the rates through the full Euler kinematics. Each fmi2DoStep integrates
 * over the communication step with RK4 in equal sub-steps of at most 2.5 ms, the inputs held over the step. It
 * starts at rest, level, heading 0. The FMU state cannot be saved (canGetAndSetFMUstate="false", as many
 * exported FMUs): those functions are exported and fail, saying so.
 *
 * Build: examples/fmu/build.sh tests/fmu/attitude attitude.fmu
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MODEL_GUID "{5a1e0c77-94d3-4b2f-8e61-2c7d0f9b3a48}"
#define DEG (3.14159265358979323846 / 180.0)
#define MAX_SUBSTEP_S 0.0025

/* Value references, as in modelDescription.xml. */
enum { VR_AILERON = 0, VR_ELEVATOR, VR_RUDDER, VR_THROTTLE, N_INPUTS };                /* inputs */
enum { VR_PHI = 10, VR_THETA, VR_PSI, VR_P, VR_Q, VR_R, VR_OUTPUT_END };                /* outputs, deg and deg/s */
enum { VR_PARAM = 100 };                                                                 /* parameters, in order */

/* The parameters (causality parameter, variability fixed), each a double in this order from VR_PARAM on. */
typedef struct {
    double roll_damping_per_s, pitch_damping_per_s, yaw_damping_per_s;
    double aileron_dps2_per_deg, elevator_dps2_per_deg, rudder_dps2_per_deg, throttle_dps2;
} parameters;
#define N_PARAMS ((int)(sizeof(parameters) / sizeof(double)))
static const parameters DEFAULTS = {1.0, 1.0, 0.5, 2.0, 2.0, 1.0, 4.0};

enum { S_PHI, S_THETA, S_PSI, S_P, S_Q, S_R, N_STATES }; /* angles in rad, rates in rad/s */
enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEPPING, MODE_TERMINATED, MODE_ERROR };

typedef struct {
    double time;
    double x[N_STATES];
    double u[N_INPUTS]; /* as set: deg, deg, deg, and the throttle 0..1 */
    parameters par;
    int mode;
    fmi2CallbackFunctions cb;
    char name[64];
} instance;

static fmi2Status say(instance *m, fmi2Status status, const char *fmt, ...) {
    if (m->cb.logger != NULL) {
        char text[300];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(text, sizeof text, fmt, ap);
        va_end(ap);
        m->cb.logger(m->cb.componentEnvironment, m->name, status, "logStatusError", "%s", text);
    }
    return status;
}

static fmi2Status unsupported(fmi2Component c, const char *fn) {
    return say(c, fmi2Error, "%s: not supported by attitude (co-simulation of Real variables, no saved state)", fn);
}

/* ---- the model ---- */

static void derivatives(const parameters *k, const double *x, const double *u, double *dx) {
    const double phi = x[S_PHI], theta = x[S_THETA], p = x[S_P], q = x[S_Q], r = x[S_R];
    dx[S_P] = -k->roll_damping_per_s * p - k->aileron_dps2_per_deg * u[VR_AILERON] * DEG;
    dx[S_Q] = -k->pitch_damping_per_s * q - k->elevator_dps2_per_deg * u[VR_ELEVATOR] * DEG +
              k->throttle_dps2 * (u[VR_THROTTLE] - 0.5) * DEG;
    dx[S_R] = -k->yaw_damping_per_s * r - k->rudder_dps2_per_deg * u[VR_RUDDER] * DEG;
    dx[S_PHI] = p + (q * sin(phi) + r * cos(phi)) * tan(theta);
    dx[S_THETA] = q * cos(phi) - r * sin(phi);
    dx[S_PSI] = (q * sin(phi) + r * cos(phi)) / cos(theta);
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
}

/* ---- FMI 2.0 ---- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n, const fmi2String categories[]) {
    (void)c, (void)loggingOn, (void)n, (void)categories;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation, (void)visible, (void)loggingOn;
    if (functions == NULL || fmuType != fmi2CoSimulation || fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions != NULL && functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error, "logStatusError",
                              "attitude: a co-simulation instance of GUID %s only", MODEL_GUID);
        }
        return NULL;
    }
    instance *m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->cb = *functions;
    snprintf(m->name, sizeof m->name, "%s", instanceName != NULL ? instanceName : "attitude");
    m->par = DEFAULTS;
    m->u[VR_THROTTLE] = 0.5;
    m->mode = MODE_INSTANTIATED;
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    ((instance *)c)->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ((instance *)c)->mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    instance *m = c;
    const double *v = (const double *)&m->par;
    for (int i = 0; i < N_PARAMS; i++) {
        if (!isfinite(v[i])) {
            m->mode = MODE_ERROR;
            return say(m, fmi2Error, "fmi2ExitInitializationMode: parameter %d is not finite", VR_PARAM + i);
        }
    }
    if (!(m->par.roll_damping_per_s > 0 && m->par.pitch_damping_per_s > 0 && m->par.yaw_damping_per_s > 0)) {
        m->mode = MODE_ERROR;
        return say(m, fmi2Error, "fmi2ExitInitializationMode: every damping must be positive");
    }
    memset(m->x, 0, sizeof m->x);
    m->mode = MODE_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ((instance *)c)->mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    instance *m = c;
    memset(m->x, 0, sizeof m->x);
    memset(m->u, 0, sizeof m->u);
    m->u[VR_THROTTLE] = 0.5;
    m->par = DEFAULTS;
    m->time = 0.0;
    m->mode = MODE_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] < N_INPUTS) {
            value[i] = m->u[vr[i]];
        } else if (vr[i] >= VR_PHI && vr[i] < VR_OUTPUT_END) {
            value[i] = m->x[vr[i] - VR_PHI] / DEG;
        } else if (vr[i] >= VR_PARAM && vr[i] < VR_PARAM + (fmi2ValueReference)N_PARAMS) {
            value[i] = ((const double *)&m->par)[vr[i] - VR_PARAM];
        } else {
            return say(m, fmi2Error, "fmi2GetReal: no Real variable has value reference %u", vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] < N_INPUTS) {
            m->u[vr[i]] = value[i];
        } else if (vr[i] >= VR_PARAM && vr[i] < VR_PARAM + (fmi2ValueReference)N_PARAMS &&
                   (m->mode == MODE_INSTANTIATED || m->mode == MODE_INITIALIZATION)) {
            ((double *)&m->par)[vr[i] - VR_PARAM] = value[i];
        } else {
            return say(m, fmi2Error, "fmi2SetReal: value reference %u cannot be set now", vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    instance *m = c;
    if (m->mode != MODE_STEPPING) {
        return say(m, fmi2Error, "fmi2DoStep: not initialized");
    }
    if (!(h > 0)) {
        return say(m, fmi2Error, "fmi2DoStep: step size %g is not positive", h);
    }
    const int n = (int)ceil(h / MAX_SUBSTEP_S - 1e-9);
    for (int i = 0; i < n; i++) {
        rk4(&m->par, m->x, m->u, h / n);
    }
    m->time = t + h;
    return fmi2OK;
}

/* ---- the rest of the FMI 2.0 API: exported, and an error ---- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return unsupported(c, "fmi2GetFMUstate"); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { (void)s; return unsupported(c, "fmi2SetFMUstate"); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { (void)s; return unsupported(c, "fmi2FreeFMUstate"); }
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *n) {
    (void)s, (void)n;
    return unsupported(c, "fmi2SerializedFMUstateSize");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n) {
    (void)s, (void)b, (void)n;
    return unsupported(c, "fmi2SerializeFMUstate");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s) {
    (void)b, (void)n, (void)s;
    return unsupported(c, "fmi2DeSerializeFMUstate");
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    (void)vr, (void)n, (void)v;
    return unsupported(c, "fmi2GetInteger");
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    (void)vr, (void)n, (void)v;
    return unsupported(c, "fmi2GetBoolean");
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    (void)vr, (void)n, (void)v;
    return unsupported(c, "fmi2GetString");
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    (void)vr, (void)n, (void)v;
    return unsupported(c, "fmi2SetInteger");
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) {
    (void)vr, (void)n, (void)v;
    return unsupported(c, "fmi2SetBoolean");
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    (void)vr, (void)n, (void)v;
    return unsupported(c, "fmi2SetString");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real du[], fmi2Real dz[]) {
    (void)u, (void)nu, (void)z, (void)nz, (void)du, (void)dz;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)n, (void)order, (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)n, (void)order, (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}
fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetStatus");
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetRealStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetStringStatus");
}
fmi2Status fmi2EnterEventMode(fmi2Component c) { return unsupported(c, "fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    (void)info;
    return unsupported(c, "fmi2NewDiscreteStates");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return unsupported(c, "fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSet, fmi2Boolean *event, fmi2Boolean *stop) {
    (void)noSet, (void)event, (void)stop;
    return unsupported(c, "fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real t) {
    (void)t;
    return unsupported(c, "fmi2SetTime");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    (void)x, (void)n;
    return unsupported(c, "fmi2SetContinuousStates");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t n) {
    (void)dx, (void)n;
    return unsupported(c, "fmi2GetDerivatives");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t n) {
    (void)z, (void)n;
    return unsupported(c, "fmi2GetEventIndicators");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    (void)x, (void)n;
    return unsupported(c, "fmi2GetContinuousStates");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal, (void)nx;
    return unsupported(c, "fmi2GetNominalsOfContinuousStates");
}
