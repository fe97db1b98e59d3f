/* fmi2_glue.h: the FMI 2.0 co-simulation glue the example FMUs share (examples/fmu/airframe, examples/fmu/pid):
 * the instance and its callbacks, logging and errors, instantiation and the mode checks around it, the FMU state
 * (a copy of the model's snapshot, serialized as its bytes behind a header), and every function of the API the
 * model does not provide, each an error naming the call.
 *
 * The model's C file defines, before including this header (examples/fmu/build.sh puts its folder on the include
 * path): MODEL_NAME ("airframe"), MODEL_STATE (the model's state in words: "an airframe state"), MODEL_GUID,
 * STATE_MAGIC and STATE_VERSION (the serialized state's header), its `parameters` with their DEFAULTS, and its
 * `snapshot`: a plain struct (no pointers) with at least `double time`, `parameters par` and `int mode`. After it,
 * the model defines fmi2ExitInitializationMode, fmi2GetReal, fmi2SetReal, fmi2DoStep and model_check_state (its own
 * checks of a deserialized state, past the header and the mode, which say why with fail()).
 */
#ifndef SILRIG_FMI2_GLUE_H
#define SILRIG_FMI2_GLUE_H

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEPPING, MODE_TERMINATED, MODE_ERROR } mode;

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

/* The model's own checks of a deserialized state (defined by the model). */
static fmi2Status model_check_state(instance *m, const snapshot *s);

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
    const char *name = instanceName != NULL ? instanceName : MODEL_NAME;
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_GUID) != 0) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              "wrong GUID %s: this binary is " MODEL_NAME " %s", fmuGUID != NULL ? fmuGUID : "(none)",
                              MODEL_GUID);
        }
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        if (functions->logger != NULL) {
            functions->logger(functions->componentEnvironment, name, fmi2Error, "logStatusError",
                              MODEL_NAME " is a co-simulation FMU only, not model exchange");
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
        return fail(m, "fmi2DeSerializeFMUstate", "%zu bytes: " MODEL_STATE " is %zu", size, sizeof(serialized));
    }
    memcpy(&in, serializedState, sizeof in);
    if (in.magic != STATE_MAGIC || in.version != STATE_VERSION || in.size != sizeof(serialized)) {
        return fail(m, "fmi2DeSerializeFMUstate", "not " MODEL_STATE " of version %u", STATE_VERSION);
    }
    if (in.s.mode < MODE_INSTANTIATED || in.s.mode > MODE_ERROR) {
        return fail(m, "fmi2DeSerializeFMUstate", "corrupt state (mode %d)", in.s.mode);
    }
    if (model_check_state(m, &in.s) != fmi2OK) {
        return fmi2Error;
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
    return fail(c, "fmi2EnterEventMode", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *fmi2eventInfo) {
    (void)fmi2eventInfo;
    return fail(c, "fmi2NewDiscreteStates", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    return fail(c, "fmi2EnterContinuousTimeMode", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return fail(c, "fmi2CompletedIntegratorStep", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    (void)time;
    return fail(c, "fmi2SetTime", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return fail(c, "fmi2SetContinuousStates", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives_[], size_t nx) {
    (void)derivatives_;
    (void)nx;
    return fail(c, "fmi2GetDerivatives", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    (void)ni;
    return fail(c, "fmi2GetEventIndicators", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    (void)x;
    (void)nx;
    return fail(c, "fmi2GetContinuousStates", MODEL_NAME " is a co-simulation FMU only");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    (void)x_nominal;
    (void)nx;
    return fail(c, "fmi2GetNominalsOfContinuousStates", MODEL_NAME " is a co-simulation FMU only");
}

#endif
