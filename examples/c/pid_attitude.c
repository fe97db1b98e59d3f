/* A PID attitude controller for silrig in C: the "bring your own controller" example, the same law as
 * examples/python/pid_attitude.py. Roll (phi) on the aileron, pitch (theta) on the elevator, yaw (psi) on the
 * rudder; the body rate is the derivative; the integrators start from the surfaces' positions when the controller
 * connects (a bumpless start) and carry the trim. Stevens & Lewis signs: a positive deflection makes a negative
 * moment. It finds what it reads and commands by name in the plant's announcement; the throttle, which it does
 * not command, stays where it is.
 *
 *   cc -std=c11 -O2 -I examples/c examples/c/pid_attitude.c -L target/release -lsilrig_client \
 *      -Wl,-rpath,"$PWD/target/release" -lm -o pid_attitude
 *   silrig run --controller-cmd ./pid_attitude configs/robust.toml
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "silrig_client.h"

static const double KP[3] = {2.0, 4.0, 8.0};       /* deg per deg: aileron, elevator, rudder */
static const double KD[3] = {0.6, 1.5, 3.0};       /* deg per deg/s */
static const double KI[3] = {1.5, 3.0, 8.0};       /* deg per deg*s */
static const double TRAVEL[3] = {21.5, 25.0, 30.0}; /* the F-16's surface travel, deg */
static const char *const ANGLE[3] = {"phi_deg", "theta_deg", "psi_deg"};
static const char *const RATE[3] = {"p_dps", "q_dps", "r_dps"};
static const char *const SURFACE[3] = {"aileron_deg", "elevator_deg", "rudder_deg"}; /* their positions now */
static const char *const INPUT[3] = {"aileron", "elevator", "rudder"};
static const char *const DIAGNOSTICS[3] = {"err_phi_deg", "err_theta_deg", "err_psi_deg"};

static int fail(const char *what, int code) {
    fprintf(stderr, "pid_attitude: %s: %s (status %d)\n", what, silrig_last_error(), code);
    return 2;
}

int main(void) {
    silrig_session *session = NULL;
    int rc = SILRIG_SESSION_OPEN(DIAGNOSTICS, 3, &session);
    if (rc != SILRIG_OK) {
        return fail("opening the session", rc);
    }
    double setpoint_deg[3];
    const double dt_s = silrig_session_dt_s(session);

    size_t angle[3], rate[3], surface[3], input[3];
    silrig_plant_info_t plant;
    for (int c = 0; c < 3 && rc == SILRIG_OK; c++) {
        if ((rc = silrig_session_signal_index(session, ANGLE[c], 0, &angle[c])) == SILRIG_OK &&
            (rc = silrig_session_signal_index(session, RATE[c], 0, &rate[c])) == SILRIG_OK &&
            (rc = silrig_session_signal_index(session, SURFACE[c], 0, &surface[c])) == SILRIG_OK) {
            rc = silrig_session_signal_index(session, INPUT[c], 1, &input[c]);
        }
    }
    if (rc == SILRIG_OK) {
        rc = silrig_session_plant_info(session, &plant);
    }
    if (rc != SILRIG_OK) {
        int failed = fail("finding the plant's signals", rc);
        silrig_session_close(session, silrig_last_error());
        return failed;
    }

    double integral[3];
    int started = 0;
    const char *saved = silrig_session_restored_checkpoint(session);
    if (saved != NULL) {
        /* Integrators of surface positions: three finite numbers within the surfaces' travel, or not ours. */
        int fits = sscanf(saved, "%lf %lf %lf", &integral[0], &integral[1], &integral[2]) == 3;
        for (int c = 0; fits && c < 3; c++) {
            fits = isfinite(integral[c]) && fabs(integral[c]) <= TRAVEL[c];
        }
        started = fits;
        silrig_session_checkpoint_used(session, fits, fits ? NULL : "not three integrators within the surfaces' travel");
    }

    silrig_plant_sample_t sample;
    for (;;) {
        rc = silrig_session_next_sample(session, &sample);
        if (rc != SILRIG_OK) {
            break; /* SILRIG_STOPPED, SILRIG_RUN_ENDED, or an error */
        }
        if (!started) {
            for (int c = 0; c < 3; c++) {
                integral[c] = sample.outputs[surface[c]];
            }
            started = 1;
        }
        double inputs[SILRIG_MAX_INPUTS], errors[3];
        silrig_session_held_command(session, inputs, plant.inputs_len);
        for (int c = 0; c < 3; c++) {
            /* The set point in force at this sample (a scenario's [[setpoint_steps]] change it during the run). */
            silrig_session_setpoint_at(session, ANGLE[c], sample.t_sim_s, &setpoint_deg[c]);
            errors[c] = setpoint_deg[c] - sample.outputs[angle[c]];
            double rate_term = KD[c] * sample.outputs[rate[c]];
            double next = integral[c] - KI[c] * errors[c] * dt_s;
            /* Anti-windup: an integrator pushing a surface past its travel stops integrating, and the command
               stays within the travel. */
            if (fabs(next - KP[c] * errors[c] + rate_term) <= TRAVEL[c] || fabs(next) < fabs(integral[c])) {
                integral[c] = next;
            }
            inputs[input[c]] = fmax(-TRAVEL[c], fmin(TRAVEL[c], integral[c] - KP[c] * errors[c] + rate_term));
        }
        rc = silrig_session_send_command(session, inputs, plant.inputs_len, errors, 3);
        if (rc < 0 && rc != SILRIG_ERR_COMMAND_REFUSED) {
            break;
        }
        if (silrig_session_checkpoint_due(session)) {
            char text[128];
            snprintf(text, sizeof text, "%.17g %.17g %.17g", integral[0], integral[1], integral[2]);
            silrig_session_save_checkpoint(session, text);
        }
    }
    int failed = rc < 0;
    if (failed) {
        fprintf(stderr, "pid_attitude: %s (status %d)\n", silrig_last_error(), rc);
    }
    int closed = silrig_session_close(session, failed ? silrig_last_error() : NULL);
    if (closed != SILRIG_OK) {
        return fail("closing the session", closed);
    }
    return failed ? 1 : 0;
}
