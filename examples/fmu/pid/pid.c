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

#define MODEL_NAME "pid"
#define MODEL_STATE "a pid state"
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

/* A deserialized state's parameters are valid and its integrators finite. */
static fmi2Status model_check_state(instance *m, const snapshot *s) {
    if (invalid_parameter(&s->par) != NULL) {
        return fail(m, "fmi2DeSerializeFMUstate", "corrupt state (mode %d)", s->mode);
    }
    for (int c2 = 0; c2 < 3; c2++) {
        if (!isfinite(s->integral[c2])) {
            return fail(m, "fmi2DeSerializeFMUstate", "corrupt state (integrator %d is not finite)", c2);
        }
    }
    return fmi2OK;
}
