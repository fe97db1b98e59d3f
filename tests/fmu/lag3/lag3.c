/* lag3: the smallest FMI 3.0 co-simulation FMU the importer's tests fly: a first-order lag y' = (gain * u - y) / tau,
 * integrated exactly over each communication step, with its state saved, serialized and restored. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#define TOKEN "{silrig-lag3-0001}"

enum { VR_TIME = 0, VR_GAIN = 1, VR_TAU = 2, VR_U = 3, VR_Y = 4 };

typedef struct {
    double time, gain, tau, u, y;
} State;

typedef struct {
    State s;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} Instance;

static void say(Instance *i, fmi3Status status, const char *message) {
    if (i->log) {
        i->log(i->env, status, "logStatusError", message);
    }
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean eventMode, fmi3Boolean earlyReturn,
                                         const fmi3ValueReference required[], size_t nRequired,
                                         fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update) {
    (void)name; (void)resources; (void)visible; (void)logging; (void)eventMode; (void)earlyReturn;
    (void)required; (void)nRequired; (void)update;
    if (!token || strcmp(token, TOKEN) != 0) {
        if (log) {
            log(env, fmi3Error, "logStatusError", "wrong instantiationToken");
        }
        return NULL;
    }
    Instance *i = calloc(1, sizeof *i);
    if (!i) {
        return NULL;
    }
    i->env = env;
    i->log = log;
    i->s.gain = 2.0;
    i->s.tau = 0.5;
    return i;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    ((Instance *)instance)->s.time = startTime;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Instance *i = instance;
    if (!(i->s.tau > 0)) {
        say(i, fmi3Error, "tau must be positive");
        return fmi3Error;
    }
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) { (void)instance; return fmi3OK; }

static double *slot(Instance *i, fmi3ValueReference vr) {
    switch (vr) {
    case VR_TIME: return &i->s.time;
    case VR_GAIN: return &i->s.gain;
    case VR_TAU: return &i->s.tau;
    case VR_U: return &i->s.u;
    case VR_Y: return &i->s.y;
    default: return NULL;
    }
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    if (nValues != nvr) {
        return fmi3Error;
    }
    for (size_t k = 0; k < nvr; k++) {
        double *p = slot(instance, vr[k]);
        if (!p) {
            say(instance, fmi3Error, "unknown value reference");
            return fmi3Error;
        }
        values[k] = *p;
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    if (nValues != nvr) {
        return fmi3Error;
    }
    for (size_t k = 0; k < nvr; k++) {
        double *p = slot(instance, vr[k]);
        if (!p || vr[k] == VR_TIME || vr[k] == VR_Y) {
            say(instance, fmi3Error, "value reference cannot be set");
            return fmi3Error;
        }
        *p = values[k];
    }
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastTime) {
    (void)noSetPrior;
    State *s = &((Instance *)instance)->s;
    double target = s->gain * s->u;
    s->y = target + (s->y - target) * exp(-h / s->tau);
    s->time = t + h;
    *eventNeeded = fmi3False;
    *terminate = fmi3False;
    *earlyReturn = fmi3False;
    *lastTime = s->time;
    return fmi3OK;
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    State *copy = *state ? *state : malloc(sizeof *copy);
    if (!copy) {
        return fmi3Error;
    }
    *copy = ((Instance *)instance)->s;
    *state = copy;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    ((Instance *)instance)->s = *(State *)state;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    (void)instance;
    free(*state);
    *state = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size) {
    (void)instance; (void)state;
    *size = sizeof(State);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state, fmi3Byte bytes[], size_t size) {
    if (size != sizeof(State)) {
        say(instance, fmi3Error, "wrong serialized size");
        return fmi3Error;
    }
    memcpy(bytes, state, sizeof(State));
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte bytes[], size_t size, fmi3FMUState *state) {
    if (size != sizeof(State)) {
        say(instance, fmi3Error, "wrong serialized size");
        return fmi3Error;
    }
    State *copy = *state ? *state : malloc(sizeof *copy);
    if (!copy) {
        return fmi3Error;
    }
    memcpy(copy, bytes, sizeof(State));
    *state = copy;
    return fmi3OK;
}
