/* misbehave: an FMI 2.0 co-simulation FMU that breaks on purpose, for the tests of silrig's FMU importer.
 *
 * The model is a first-order lag, y' = -y + u (y(0) = 0), stepped exactly. From the communication point
 * fault_time_s on (the first fmi2DoStep whose currentCommunicationPoint is at or past it), the parameter `fault`
 * picks what goes wrong:
 *   0 nothing;
 *   1 fmi2DoStep returns fmi2Error;
 *   2 fmi2DoStep returns fmi2Discard (fmi2GetRealStatus(fmi2LastSuccessfulTime) gives the time reached,
 *     fmi2GetBooleanStatus(fmi2Terminated) fmi2True);
 *   3 fmi2DoStep returns fmi2Fatal;
 *   4 fmi2DoStep writes through a null pointer (SIGSEGV);
 *   5 the output y reads NaN (fmi2DoStep returns fmi2OK);
 *   6 fmi2DoStep sleeps 15 ms before it steps (slower than silrig's 10 ms period), then returns fmi2OK.
 * Each failing call says what it does through the logger callback. `fault` is a Real (so an importer that sets only
 * Real parameters can set it): anything but a whole number 0..6 fails fmi2ExitInitializationMode.
 *
 * Build: examples/fmu/build.sh tests/fmu/misbehave misbehave.fmu
 */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#define MODEL_GUID "{3d9f7c21-6b4a-4e8f-a5c2-0e7b19d4f630}"

enum { VR_U = 0, VR_Y = 1, VR_FAULT = 10, VR_FAULT_TIME = 11 };
enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEPPING, MODE_TERMINATED, MODE_BROKEN };

/* An FMU state: plain values, copied and serialized as they are. */
typedef struct {
    double time, y, u, fault, fault_time_s;
    int mode, nan_output, fault_started, reserved; /* reserved: 0, so a serialized state has no unset bytes */
} snapshot;

#define STATE_MAGIC 0x4d495342u /* "MISB" */
typedef struct {
    unsigned int magic, size;
    snapshot s;
} serialized;

typedef struct {
    snapshot s;
    fmi2CallbackFunctions cb;
    char name[64];
} instance;

/* The null pointer fault 4 writes through, behind a volatile so that the compiler cannot see it is null. */
static int *volatile null_target = NULL;

static fmi2Status say(instance *m, fmi2Status status, const char *fmt, ...) {
    if (m->cb.logger != NULL) {
        char text[300];
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(text, sizeof text, fmt, ap);
        va_end(ap);
        m->cb.logger(m->cb.componentEnvironment, m->name, status, status == fmi2OK ? "logAll" : "logStatusError",
                     "%s", text);
    }
    return status;
}

static fmi2Status unsupported(fmi2Component c, const char *fn) {
    return say(c, fmi2Error, "%s: not supported by misbehave (a co-simulation FMU of Real variables)", fn);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t n, const fmi2String categories[]) {
    (void)c;
    (void)loggingOn;
    (void)n;
    (void)categories;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
    (void)visible;
    (void)loggingOn;
    if (functions == NULL) {
        return NULL;
    }
    const char *name = instanceName != NULL ? instanceName : "misbehave";
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "wrong GUID %s: this binary is misbehave %s", fmuGUID != NULL ? fmuGUID : "(none)",
                              MODEL_GUID);
        }
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "misbehave is a co-simulation FMU only");
        }
        return NULL;
    }
    instance *m = functions->allocateMemory != NULL ? functions->allocateMemory(1, sizeof *m) : calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    memset(m, 0, sizeof *m);
    m->cb = *functions;
    snprintf(m->name, sizeof m->name, "%s", name);
    m->s.fault_time_s = 1.0;
    m->s.mode = MODE_INSTANTIATED;
    return m;
}

void fmi2FreeInstance(fmi2Component c) {
    instance *m = c;
    if (m == NULL) {
        return;
    }
    if (m->cb.freeMemory != NULL) {
        m->cb.freeMemory(m);
    } else {
        free(m);
    }
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    ((instance *)c)->s.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    ((instance *)c)->s.mode = MODE_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    instance *m = c;
    double f = m->s.fault;
    if (!(f >= 0.0 && f <= 6.0 && f == floor(f)) || !isfinite(m->s.fault_time_s)) {
        m->s.mode = MODE_BROKEN;
        return say(m, fmi2Error, "fmi2ExitInitializationMode: fault must be a whole number 0..6 (is %g) and "
                                 "fault_time_s finite (is %g)", f, m->s.fault_time_s);
    }
    m->s.mode = MODE_STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    ((instance *)c)->s.mode = MODE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    instance *m = c;
    memset(&m->s, 0, sizeof m->s);
    m->s.fault_time_s = 1.0;
    m->s.mode = MODE_INSTANTIATED;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case VR_U: value[i] = m->s.u; break;
        case VR_Y: value[i] = m->s.nan_output ? NAN : m->s.y; break;
        case VR_FAULT: value[i] = m->s.fault; break;
        case VR_FAULT_TIME: value[i] = m->s.fault_time_s; break;
        default: return say(m, fmi2Error, "fmi2GetReal: no variable has value reference %u", vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    instance *m = c;
    for (size_t i = 0; i < nvr; i++) {
        int parameter = vr[i] == VR_FAULT || vr[i] == VR_FAULT_TIME;
        if (parameter && m->s.mode != MODE_INSTANTIATED && m->s.mode != MODE_INITIALIZATION) {
            return say(m, fmi2Error, "fmi2SetReal: parameter %u is fixed after initialization", vr[i]);
        }
        switch (vr[i]) {
        case VR_U: m->s.u = value[i]; break;
        case VR_FAULT: m->s.fault = value[i]; break;
        case VR_FAULT_TIME: m->s.fault_time_s = value[i]; break;
        default: return say(m, fmi2Error, "fmi2SetReal: value reference %u is no input or parameter", vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    instance *m = c;
    if (m->s.mode != MODE_STEPPING) {
        return say(m, fmi2Error, "fmi2DoStep: not initialized, terminated, or failed before");
    }
    if (m->s.fault != 0.0 && t >= m->s.fault_time_s - 1e-9) {
        if (!m->s.fault_started && m->s.fault >= 5.0) {
            say(m, fmi2Warning, m->s.fault == 5.0 ? "fault 5 from t = %g s: y reads NaN"
                                                  : "fault 6 from t = %g s: each fmi2DoStep sleeps 15 ms first", t);
        }
        m->s.fault_started = 1;
        switch ((int)m->s.fault) {
        case 1:
            return say(m, fmi2Error, "fault 1 at t = %g s: fmi2DoStep returns fmi2Error", t);
        case 2:
            m->s.mode = MODE_BROKEN;
            return say(m, fmi2Discard, "fault 2 at t = %g s: fmi2DoStep returns fmi2Discard", t);
        case 3:
            m->s.mode = MODE_BROKEN;
            return say(m, fmi2Fatal, "fault 3 at t = %g s: fmi2DoStep returns fmi2Fatal", t);
        case 4:
            say(m, fmi2Warning, "fault 4 at t = %g s: fmi2DoStep writes through a null pointer", t);
            *null_target = 4;
            return fmi2Fatal; /* not reached */
        case 5:
            m->s.nan_output = 1;
            break;
        case 6: {
            struct timespec nap = {0, 15000000};
            while (nanosleep(&nap, &nap) != 0) {
            }
            break;
        }
        default:
            break;
        }
    }
    m->s.y = m->s.u + (m->s.y - m->s.u) * exp(-h);
    m->s.time = t + h;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    instance *m = c;
    if (s != fmi2LastSuccessfulTime) {
        return say(m, fmi2Error, "fmi2GetRealStatus: no status of kind %d", (int)s);
    }
    *value = m->s.time;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    instance *m = c;
    if (s != fmi2Terminated) {
        return say(m, fmi2Error, "fmi2GetBooleanStatus: no status of kind %d", (int)s);
    }
    *value = m->s.mode == MODE_BROKEN ? fmi2True : fmi2False;
    return fmi2OK;
}

/* FMU state: a copy of the snapshot; serialized as its bytes behind a magic number and the size. */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    instance *m = c;
    if (*state == NULL) {
        *state = m->cb.allocateMemory != NULL ? m->cb.allocateMemory(1, sizeof(snapshot)) : calloc(1, sizeof(snapshot));
        if (*state == NULL) {
            return say(m, fmi2Error, "fmi2GetFMUstate: out of memory");
        }
    }
    memcpy(*state, &m->s, sizeof(snapshot));
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    instance *m = c;
    if (state == NULL) {
        return say(m, fmi2Error, "fmi2SetFMUstate: no state");
    }
    memcpy(&m->s, state, sizeof(snapshot));
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    instance *m = c;
    if (state != NULL && *state != NULL) {
        if (m->cb.freeMemory != NULL) {
            m->cb.freeMemory(*state);
        } else {
            free(*state);
        }
        *state = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)c;
    (void)state;
    *size = sizeof(serialized);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    if (state == NULL || size < sizeof(serialized)) {
        return say(c, fmi2Error, "fmi2SerializeFMUstate: no state, or a buffer of %zu bytes", size);
    }
    serialized out;
    memset(&out, 0, sizeof out);
    out.magic = STATE_MAGIC;
    out.size = sizeof(serialized);
    memcpy(&out.s, state, sizeof(snapshot));
    memcpy(bytes, &out, sizeof out);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    serialized in;
    if (size != sizeof(serialized)) {
        return say(c, fmi2Error, "fmi2DeSerializeFMUstate: %zu bytes, a misbehave state is %zu", size, sizeof in);
    }
    memcpy(&in, bytes, sizeof in);
    if (in.magic != STATE_MAGIC || in.size != sizeof(serialized)) {
        return say(c, fmi2Error, "fmi2DeSerializeFMUstate: not a misbehave state");
    }
    fmi2Status got = fmi2GetFMUstate(c, state); /* allocates one if needed */
    if (got != fmi2OK) {
        return got;
    }
    memcpy(*state, &in.s, sizeof(snapshot));
    return fmi2OK;
}

/* The rest of the FMI 2.0 API: exported, and an error. */
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
                                        const fmi2ValueReference k[], size_t nk, const fmi2Real dk[], fmi2Real du[]) {
    (void)u, (void)nu, (void)k, (void)nk, (void)dk, (void)du;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    (void)vr, (void)n, (void)order, (void)v;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real v[]) {
    (void)vr, (void)n, (void)order, (void)v;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}
fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    (void)s, (void)v;
    return unsupported(c, "fmi2GetIntegerStatus");
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
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    (void)x, (void)n;
    return unsupported(c, "fmi2GetNominalsOfContinuousStates");
}
