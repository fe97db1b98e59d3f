/* pid: the example PID attitude controller as an FMI 2.0 co-simulation FMU, for silrig's `--controller-fmu`. The
 * same law and F-16 gains as examples/c/pid_attitude.c: roll (phi) on the aileron, pitch (theta) on the elevator,
 * yaw (psi) on the rudder; the body rate is the derivative; the integrators start from the surfaces' positions at
 * the first step (a bumpless start) and carry the trim; an integrator pushing its surface past its travel stops
 * integrating, and each command stays within the travel. Stevens & Lewis signs: a positive deflection makes a
 * negative moment.
 *
 * Inputs are named like the plant's outputs it reads (phi_deg ... rudder_deg) and the set points it follows
 * (phi_deg_sp, theta_deg_sp, psi_deg_sp: silrig feeds `<output>_sp` the scenario's set point of that output);
 * outputs are named like the plant's inputs it commands (aileron, elevator, rudder), and its errors
 * (err_phi_deg ...) are further outputs, which silrig logs as diagnostics. The gains are parameters
 * (`[controller.parameters]`). Its state (integrators, whether it has started, the last outputs) is a plain struct:
 * fmi2GetFMUstate copies it, fmi2SerializeFMUstate writes its bytes behind a header that fmi2DeSerializeFMUstate
 * checks. A sampled controller needs no time: a communication point may jump forward (a skipped sample, a
 * restart from a checkpoint), never back.
 *
 * Build: examples/fmu/build.sh examples/fmu/pid pid.fmu
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MODEL_GUID "{5d0c7e21-93a4-4b6f-8e1d-2c7b9a4f6e03}"

/* Value references, as in modelDescription.xml. */
enum {
    VR_PHI = 0, VR_THETA, VR_PSI, VR_P, VR_Q, VR_R,                      /* inputs: angles deg, rates deg/s */
    VR_AILERON_POS, VR_ELEVATOR_POS, VR_RUDDER_POS,                      /* inputs: the surfaces now, deg */
    VR_PHI_SP, VR_THETA_SP, VR_PSI_SP, VR_INPUT_END,                     /* inputs: set points, deg */
    VR_AILERON = 20, VR_ELEVATOR, VR_RUDDER,                             /* outputs: commands, deg */
    VR_ERR_PHI, VR_ERR_THETA, VR_ERR_PSI, VR_OUTPUT_END,                 /* outputs: errors, deg */
    VR_PARAM = 100 /* the parameters, in the order of struct parameters */
};
#define N_INPUTS (VR_INPUT_END - VR_PHI)
#define N_OUTPUTS (VR_OUTPUT_END - VR_AILERON)

/* The gains and travels per channel (roll/aileron, pitch/elevator, yaw/rudder), each a double from VR_PARAM on. */
typedef struct {
    double kp[3]; /* deg per deg */
    double kd[3]; /* deg per deg/s */
    double ki[3]; /* deg per deg*s */
    double travel_deg[3];
} parameters;
#define N_PARAMS ((int)(sizeof(parameters) / sizeof(double)))

/* examples/c/pid_attitude.c's: KP, KD, KI and the F-16's surface travel. */
static const parameters DEFAULTS = {
    {2.0, 4.0, 8.0},
    {0.6, 1.5, 3.0},
    {1.5, 3.0, 8.0},
    {21.5, 25.0, 30.0},
};

typedef enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEPPING, MODE_TERMINATED, MODE_ERROR } mode;

/* Everything an FMU state holds: a plain struct, copied by value (no pointers), serialized as its bytes. */
typedef struct {
    double time;
    double in[N_INPUTS];
    double out[N_OUTPUTS];
    double integral[3];
    parameters par;
    int started; /* the integrators have taken the surfaces' positions */
    int mode;
} snapshot;

#define STATE_MAGIC 0x50494446u /* "FDIP" */
#define STATE_VERSION 1u
typedef struct {
    unsigned int magic, version, size, reserved;
    snapshot s;
} serialized;

typedef struct {
    snapshot s;
    fmi2CallbackFunctions cb;
    char *name;
    int logging_on;
} instance;

static void log_msg(instance *m, fmi2Status status, const char *category, const char *fmt, ...) {
    if (m->cb.logger == NULL || (status == fmi2OK && !m->logging_on)) {
        return;
    }
    char text[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    m->cb.logger(m->cb.componentEnvironment, m->name, status, category, "%s", text);
}

static void *allocate(const fmi2CallbackFunctions *cb, size_t n) {
    return cb->allocateMemory != NULL ? cb->allocateMemory(n, 1) : calloc(n, 1);
}

static void release(const fmi2CallbackFunctions *cb, void *p) {
    if (p == NULL) {
        return;
    }
    if (cb->freeMemory != NULL) {
        cb->freeMemory(p);
    } else {
        free(p);
    }
}

static fmi2Status fail(instance *m, const char *fn, const char *fmt, ...) {
    char text[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    log_msg(m, fmi2Error, "logStatusError", "%s: %s", fn, text);
    return fmi2Error;
}

/* ---- the law ---- */

static const char *invalid_parameter(const parameters *k) {
    static const char *const names[] = {"kp_phi",  "kp_theta", "kp_psi",  "kd_phi",
                                        "kd_theta", "kd_psi",  "ki_phi",  "ki_theta",
                                        "ki_psi",  "travel_aileron_deg", "travel_elevator_deg",
                                        "travel_rudder_deg"};
    const double *v = (const double *)k;
    for (int i = 0; i < N_PARAMS; i++) {
        if (!isfinite(v[i]) || (i >= 9 && !(v[i] > 0))) {
            return names[i];
        }
    }
    return NULL;
}

/* One step of examples/c/pid_attitude.c's loop, term for term in the same order (so the same inputs give the
 * same bits). */
static void step(snapshot *s, double dt_s) {
    const double *in = s->in;
    const parameters *k = &s->par;
    if (!s->started) {
        for (int c = 0; c < 3; c++) {
            s->integral[c] = in[VR_AILERON_POS + c];
        }
        s->started = 1;
    }
    for (int c = 0; c < 3; c++) {
        double error = in[VR_PHI_SP + c] - in[VR_PHI + c];
        double rate_term = k->kd[c] * in[VR_P + c];
        double next = s->integral[c] - k->ki[c] * error * dt_s;
        if (fabs(next - k->kp[c] * error + rate_term) <= k->travel_deg[c] || fabs(next) < fabs(s->integral[c])) {
            s->integral[c] = next;
        }
        s->out[c] = fmax(-k->travel_deg[c], fmin(k->travel_deg[c], s->integral[c] - k->kp[c] * error + rate_term));
        s->out[3 + c] = error;
    }
}

/* ---- FMI 2.0: common functions ---- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories;
    (void)categories;
    ((instance *)c)->logging_on = loggingOn != fmi2False;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    if (functions == NULL) {
        return NULL;
    }
    const char *name = instanceName != NULL ? instanceName : "pid";
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "wrong GUID %s: this binary is pid %s", fmuGUID != NULL ? fmuGUID : "(none)",
                              MODEL_GUID);
        }
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "pid is a co-simulation FMU only, not model exchange");
        }
        return NULL;
    }
    instance *m = allocate(functions, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    memset(m, 0, sizeof *m);
    m->cb = *functions;
    m->name = allocate(functions, strlen(name) + 1);
    if (m->name == NULL) {
        release(functions, m);
        return NULL;
    }
    strcpy(m->name, name);
    m->logging_on = loggingOn != fmi2False;
    m->s.par = DEFAULTS;
    m->s.mode = MODE_INSTANTIATED;
    return m;
}

void fmi2FreeInstance(fmi2Component c) {
    instance *m = c;
    if (m == NULL) {
        return;
    }
    fmi2CallbackFunctions cb = m->cb;
    release(&cb, m->name);
    release(&cb, m);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    instance *m = c;
    if (m->s.mode != MODE_INSTANTIATED) {
        return fail(m, "fmi2SetupExperiment", "only after fmi2Instantiate");
    }
    m->s.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    instance *m = c;
    if (m->s.mode != MODE_INSTANTIATED) {
        return fail(m, "fmi2EnterInitializationMode", "only after fmi2Instantiate");
    }
    m->s.mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    instance *m = c;
    if (m->s.mode != MODE_INITIALIZATION) {
        return fail(m, "fmi2ExitInitializationMode", "not in initialization mode");
    }
    const char *bad = invalid_parameter(&m->s.par);
    if (bad != NULL) {
        m->s.mode = MODE_ERROR;
        return fail(m, "fmi2ExitInitializationMode", "invalid parameter %s (gains finite, travels positive)", bad);
    }
    /* Until the first step: no error, and each command where its surface is. */
    for (int c2 = 0; c2 < 3; c2++) {
        m->s.out[c2] = m->s.in[VR_AILERON_POS + c2];
        m->s.out[3 + c2] = 0.0;
    }
    m->s.mode = MODE_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    instance *m = c;
    m->s.mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    instance *m = c;
    memset(&m->s, 0, sizeof m->s);
    m->s.par = DEFAULTS;
    m->s.mode = MODE_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] < VR_INPUT_END) {
            value[i] = m->s.in[vr[i]];
        } else if (vr[i] >= VR_AILERON && vr[i] < VR_OUTPUT_END) {
            value[i] = m->s.out[vr[i] - VR_AILERON];
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
        if (vr[i] < VR_INPUT_END) {
            m->s.in[vr[i]] = value[i];
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

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "fmi2GetInteger", "no Integer variable (value reference %u)", vr[0]);
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "fmi2GetBoolean", "no Boolean variable (value reference %u)", vr[0]);
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "fmi2GetString", "no String variable (value reference %u)", vr[0]);
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "fmi2SetInteger", "no Integer variable (value reference %u)", vr[0]);
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "fmi2SetBoolean", "no Boolean variable (value reference %u)", vr[0]);
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    (void)value;
    return nvr == 0 ? fmi2OK : fail(c, "fmi2SetString", "no String variable (value reference %u)", vr[0]);
}

/* ---- FMU state: a copy of the snapshot, serialized as its bytes behind a header ---- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    instance *m = c;
    if (*FMUstate == NULL) {
        *FMUstate = allocate(&m->cb, sizeof(snapshot));
        if (*FMUstate == NULL) {
            return fail(m, "fmi2GetFMUstate", "out of memory");
        }
    }
    memcpy(*FMUstate, &m->s, sizeof(snapshot));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    instance *m = c;
    if (FMUstate == NULL) {
        return fail(m, "fmi2SetFMUstate", "no state given");
    }
    memcpy(&m->s, FMUstate, sizeof(snapshot));
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    instance *m = c;
    if (FMUstate != NULL) {
        release(&m->cb, *FMUstate);
        *FMUstate = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    (void)c;
    (void)FMUstate;
    *size = sizeof(serialized);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    instance *m = c;
    if (FMUstate == NULL || size < sizeof(serialized)) {
        return fail(m, "fmi2SerializeFMUstate", "no state, or a buffer of %zu bytes (needs %zu)", size,
                    sizeof(serialized));
    }
    serialized out;
    memset(&out, 0, sizeof out);
    out.magic = STATE_MAGIC;
    out.version = STATE_VERSION;
    out.size = (unsigned int)sizeof(serialized);
    memcpy(&out.s, FMUstate, sizeof(snapshot));
    memcpy(serializedState, &out, sizeof out);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    instance *m = c;
    serialized in;
    if (size != sizeof(serialized)) {
        return fail(m, "fmi2DeSerializeFMUstate", "%zu bytes: a pid state is %zu", size, sizeof(serialized));
    }
    memcpy(&in, serializedState, sizeof in);
    if (in.magic != STATE_MAGIC || in.version != STATE_VERSION || in.size != sizeof(serialized)) {
        return fail(m, "fmi2DeSerializeFMUstate", "not a pid state of version %u", STATE_VERSION);
    }
    if (in.s.mode < MODE_INSTANTIATED || in.s.mode > MODE_ERROR || invalid_parameter(&in.s.par) != NULL) {
        return fail(m, "fmi2DeSerializeFMUstate", "corrupt state (mode %d)", in.s.mode);
    }
    for (int c2 = 0; c2 < 3; c2++) {
        if (!isfinite(in.s.integral[c2])) {
            return fail(m, "fmi2DeSerializeFMUstate", "corrupt state (integrator %d is not finite)", c2);
        }
    }
    if (*FMUstate == NULL) {
        *FMUstate = allocate(&m->cb, sizeof(snapshot));
        if (*FMUstate == NULL) {
            return fail(m, "fmi2DeSerializeFMUstate", "out of memory");
        }
    }
    memcpy(*FMUstate, &in.s, sizeof(snapshot));
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return fail(c, "fmi2GetDirectionalDerivative", "not provided (providesDirectionalDerivative is false)");
}

/* ---- FMI 2.0 co-simulation ---- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return fail(c, "fmi2SetRealInputDerivatives", "not provided (canInterpolateInputs is false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return fail(c, "fmi2GetRealOutputDerivatives", "not provided (maxOutputDerivativeOrder is 0)");
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
    /* Forward jumps are fine for a sampled law (see the top); going back in time is not. */
    if (!(currentCommunicationPoint >= m->s.time - 1e-9 * fmax(1.0, fabs(m->s.time)))) {
        return fail(m, "fmi2DoStep", "communication point %.17g is before the FMU's time %.17g",
                    currentCommunicationPoint, m->s.time);
    }
    for (int i = 0; i < N_INPUTS; i++) {
        if (!isfinite(m->s.in[i])) {
            return fail(m, "fmi2DoStep", "input with value reference %d is not finite", i);
        }
    }
    step(&m->s, communicationStepSize);
    m->s.time = currentCommunicationPoint + communicationStepSize;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return fail(c, "fmi2CancelStep", "fmi2DoStep never returns fmi2Pending");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)value;
    return fail(c, "fmi2GetStatus", "no status of kind %d: fmi2DoStep never returns fmi2Pending", (int)s);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    instance *m = c;
    if (s == fmi2LastSuccessfulTime) {
        *value = m->s.time;
        return fmi2OK;
    }
    return fail(m, "fmi2GetRealStatus", "no Real status of kind %d", (int)s);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)value;
    return fail(c, "fmi2GetIntegerStatus", "no Integer status of kind %d", (int)s);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    instance *m = c;
    if (s == fmi2Terminated) {
        *value = m->s.mode == MODE_ERROR ? fmi2True : fmi2False;
        return fmi2OK;
    }
    return fail(m, "fmi2GetBooleanStatus", "no Boolean status of kind %d", (int)s);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)value;
    return fail(c, "fmi2GetStringStatus", "no String status of kind %d", (int)s);
}

/* ---- FMI 2.0 model exchange: not this FMU's interface ---- */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    return fail(c, "fmi2EnterEventMode", "pid is a co-simulation FMU only");
}
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *fmi2eventInfo) {
    (void)fmi2eventInfo;
    return fail(c, "fmi2NewDiscreteStates", "pid is a co-simulation FMU only");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    return fail(c, "fmi2EnterContinuousTimeMode", "pid is a co-simulation FMU only");
}
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return fail(c, "fmi2CompletedIntegratorStep", "pid is a co-simulation FMU only");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)time;
    return fail(c, "fmi2SetTime", "pid is a co-simulation FMU only");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return fail(c, "fmi2SetContinuousStates", "pid is a co-simulation FMU only");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives_[], size_t nx) {
    (void)derivatives_;
    (void)nx;
    return fail(c, "fmi2GetDerivatives", "pid is a co-simulation FMU only");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    (void)ni;
    return fail(c, "fmi2GetEventIndicators", "pid is a co-simulation FMU only");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return fail(c, "fmi2GetContinuousStates", "pid is a co-simulation FMU only");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal;
    (void)nx;
    return fail(c, "fmi2GetNominalsOfContinuousStates", "pid is a co-simulation FMU only");
}
