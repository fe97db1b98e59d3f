/* What tests/fmu/stair and tests/fmu/resource share: the smallest FMI 3.0 co-simulation FMU whose outputs are Int32,
 * around three hooks the including file defines before including this one:
 *
 *   #define TOKEN "{...}"                        its instantiationToken
 *   static int model_start(Model *m, const char *resources)    at instantiation (resources: the folder, ending in /);
 *                                                              0 when it cannot start (it logs why)
 *   static void model_step(Model *m, double time_s)            after each step, at the step's end time
 *   static int *model_int32(Model *m, fmi3ValueReference vr)   an Int32 output by value reference, or NULL
 *
 * with `typedef struct {...} Model;` and `char error[200]` in it for model_start's reason. Value reference 0 is the
 * time (Float64, independent). The FMU keeps no state an importer can save (canGetAndSetFMUState is false): those
 * functions answer fmi3Error, as do all the others it does not offer, from lag3's unsupported.c, which each FMU's
 * own unsupported.c compiles (a translation unit of its own: its stubs are declared without the header). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

typedef struct {
    double time;
    Model m;
} Instance;

fmi3Instance fmi3InstantiateCoSimulation(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                         fmi3Boolean logging, fmi3Boolean eventMode, fmi3Boolean earlyReturn,
                                         const fmi3ValueReference required[], size_t nRequired,
                                         fmi3InstanceEnvironment env, fmi3LogMessageCallback log,
                                         fmi3IntermediateUpdateCallback update) {
    (void)name; (void)visible; (void)logging; (void)eventMode; (void)earlyReturn; (void)required; (void)nRequired;
    (void)update;
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
    if (!model_start(&i->m, resources ? resources : "")) {
        if (log) {
            log(env, fmi3Error, "logStatusError", i->m.error);
        }
        free(i);
        return NULL;
    }
    return i;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    Instance *i = instance;
    i->time = startTime;
    model_step(&i->m, startTime);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) { (void)instance; return fmi3OK; }

fmi3Status fmi3Terminate(fmi3Instance instance) { (void)instance; return fmi3OK; }

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues) {
    for (size_t k = 0; k < nvr && k < nValues; k++) {
        if (vr[k] != 0) {
            return fmi3Error;
        }
        values[k] = ((Instance *)instance)->time;
    }
    return nValues == nvr ? fmi3OK : fmi3Error;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    (void)instance; (void)vr; (void)nvr; (void)values; (void)nValues;
    return fmi3Error; /* no Float64 input or parameter */
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues) {
    if (nValues != nvr) {
        return fmi3Error;
    }
    for (size_t k = 0; k < nvr; k++) {
        int *p = model_int32(&((Instance *)instance)->m, vr[k]);
        if (!p) {
            return fmi3Error;
        }
        values[k] = *p;
    }
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean noSetPrior,
                      fmi3Boolean *eventNeeded, fmi3Boolean *terminate, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastTime) {
    (void)noSetPrior;
    Instance *i = instance;
    i->time = t + h;
    model_step(&i->m, i->time);
    *eventNeeded = fmi3False;
    *terminate = fmi3False;
    *earlyReturn = fmi3False;
    *lastTime = i->time;
    return fmi3OK;
}

