/* A plant of your own in C for silrig: the "bring your own plant" example, the same model as
 * tests/clients/toy_plant.py. Three decoupled rotational axes (roll, pitch, yaw), each a damped double integrator
 * driven by its surface, with the F-16's sign convention (a positive deflection makes a negative moment) and the
 * F-16's signal names, so the example controllers fly it unchanged. The rig keeps the clock, the watchdog, the
 * failsafe (the hold values announced below), the faults, the logger and the timing report.
 *
 *   cc -std=c11 -O2 -I examples/c examples/c/toy_plant.c -L target/release -lsilrig_client \
 *      -Wl,-rpath,"$PWD/target/release" -o toy_plant
 *   silrig run --plant-cmd ./toy_plant --controller-cmd "python3 examples/python/pid_attitude.py"
 */
#include <stdio.h>
#include <string.h>

#include "silrig_client.h"

#define N_OUT 9
#define N_IN 3

/* Parameters, each overridable from the scenario's [plant.parameters] by the same name. */
static double gain_dps2_per_deg = 4.0; /* angular acceleration per deg of surface */
static double damping_per_s = 1.0;

static const char *const OUT_NAME[N_OUT] = {"phi_deg",     "theta_deg",    "psi_deg",
                                            "p_dps",       "q_dps",        "r_dps",
                                            "aileron_deg", "elevator_deg", "rudder_deg"};
static const char *const OUT_UNIT[N_OUT] = {"deg", "deg", "deg", "deg/s", "deg/s", "deg/s", "deg", "deg", "deg"};
static const char *const IN_NAME[N_IN] = {"aileron", "elevator", "rudder"};

/* The announcement: names and units NUL-padded, every output and command in the trace, surfaces +-30 deg with a
 * failsafe hold of 0, each reporting its position as outputs 6..8. */
static void announce(silrig_plant_info_t *info) {
    memset(info, 0, sizeof *info);
    strcpy((char *)info->plant_name, "toy_c");
    info->outputs_len = N_OUT;
    info->inputs_len = N_IN;
    for (int k = 0; k < N_OUT; k++) {
        strcpy((char *)info->output_names[k], OUT_NAME[k]);
        strcpy((char *)info->output_units[k], OUT_UNIT[k]);
        info->output_flags[k] = SILRIG_OUTPUT_IN_TRACE;
    }
    for (int k = 0; k < N_IN; k++) {
        strcpy((char *)info->input_names[k], IN_NAME[k]);
        strcpy((char *)info->input_units[k], "deg");
        info->input_min[k] = -30.0;
        info->input_max[k] = 30.0;
        info->input_hold[k] = 0.0;
        info->input_held_output[k] = (uint32_t)(6 + k);
        info->input_flags[k] = SILRIG_INPUT_COMMAND_IN_TRACE;
    }
}

/* The scenario's value of a parameter, or the model's own when it gives none. */
static int read_parameter(const char *name, double *value) {
    int rc = silrig_plant_parameter(name, value);
    if (rc != SILRIG_OK && rc != SILRIG_NOT_GIVEN) {
        fprintf(stderr, "toy_plant: reading parameter %s: %s (status %d)\n", name, silrig_last_error(), rc);
        return 0;
    }
    return 1;
}

int main(void) {
    if (!read_parameter("gain_dps2_per_deg", &gain_dps2_per_deg) || !read_parameter("damping_per_s", &damping_per_s)) {
        return 2;
    }
    silrig_plant_info_t info;
    announce(&info);
    silrig_plant_session *plant = NULL;
    int rc = SILRIG_PLANT_OPEN(&info, &plant);
    if (rc != SILRIG_OK) {
        fprintf(stderr, "toy_plant: opening the plant session: %s (status %d)\n", silrig_last_error(), rc);
        return 2;
    }
    const double dt_s = silrig_plant_dt_s(plant);
    double angle[3] = {0}, rate[3] = {0}, surface[3] = {0};
    double outputs[N_OUT], inputs[N_IN];
    for (;;) {
        for (int c = 0; c < 3; c++) {
            outputs[c] = angle[c];
            outputs[3 + c] = rate[c];
            outputs[6 + c] = surface[c];
        }
        rc = silrig_plant_tick(plant, outputs, N_OUT, inputs, N_IN);
        if (rc != SILRIG_OK) {
            break; /* SILRIG_RUN_ENDED, SILRIG_STOPPED, or an error */
        }
        for (int c = 0; c < 3; c++) {
            surface[c] = inputs[c];
            rate[c] += (-gain_dps2_per_deg * inputs[c] - damping_per_s * rate[c]) * dt_s;
            angle[c] += rate[c] * dt_s;
        }
    }
    int failed = rc < 0;
    if (failed) {
        fprintf(stderr, "toy_plant: %s (status %d)\n", silrig_last_error(), rc);
    }
    int closed = silrig_plant_close(plant, failed ? silrig_last_error() : NULL);
    return failed || closed != SILRIG_OK ? 1 : 0;
}
