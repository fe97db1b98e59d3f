/* silrig_client.h: fly your own controller in a silrig run through libsilrig_client.so.
 *
 * The library is silrig's own controller session (the one silrig-controller uses) behind a C ABI. It opens the
 * run named by the SILRIG_* environment variables (silrig run --controller-cmd sets them; for --controller
 * external, `. <out>/controller.env`), tells which signals the plant announced (find yours by name, never by
 * position: silrig_session_signal_index), hands out one plant sample at a time and sends one command in answer to
 * each. It stamps and validates every command, applies the run's in-loop faults (delay, jitter, drop), blends
 * bumplessly after a restart, watches the plant, writes the controller's timing report and turns SIGTERM/SIGINT
 * and the end of the run into return codes.
 *
 * Build:  cc -I examples/c my_controller.c -L target/release -lsilrig_client -Wl,-rpath,$PWD/target/release
 * Run:    silrig run --controller-cmd ./my_controller
 *
 * Return codes: every function returning int returns one of the SILRIG_* status codes of silrig_contract.h
 * (0 and above are not errors; below 0, silrig_last_error() says why, naming the problem).
 *
 * Ownership: the session belongs to the caller from silrig_session_open until silrig_session_close, which frees
 * it; strings the library returns belong to the library (copy them if you keep them). The library keeps no
 * pointer the caller passed in after a call returns.
 *
 * Threads: use a session only from the thread that opened it (its shared-memory ports are bound to that thread);
 * one session per process. silrig_last_error() is per thread.
 *
 * Signals: opening a session installs handlers for SIGTERM and SIGINT that only set a flag; the next
 * silrig_session_next_sample returns SILRIG_STOPPED. Close the session then, so its report is written.
 */
#ifndef SILRIG_CLIENT_H
#define SILRIG_CLIENT_H

#include "silrig_contract.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One controller's session in one run; opaque. */
typedef struct SilrigSession silrig_session;

/* The wire layout version the library speaks (compare with SILRIG_WIRE_LAYOUT_VERSION). */
uint32_t silrig_layout_version(void);

/* Why the last failing call on this thread failed ("" if none). Owned by the library; valid until the next
 * call on this thread. */
const char *silrig_last_error(void);

/* Open the run's controller session (use SILRIG_SESSION_OPEN, which passes the contract this file was built
 * against). Announces the names of the diagnostics the controller will send with each command (at most
 * SILRIG_MAX_DIAGNOSTICS, each 1..31 ASCII letters, digits or _; they label the trace's columns and
 * plots). On success *session_out is the session; on failure NULL, with SILRIG_ERR_LAYOUT (built against another
 * layout version or sample sizes), SILRIG_ERR_SETUP (SILRIG_* variables or scenario unusable, bad names) or
 * SILRIG_ERR_SECOND_CONTROLLER (the run has a controller). */
int silrig_session_open(uint32_t layout_version, size_t plant_sample_size, size_t command_sample_size,
                        const char *const *diagnostic_names, size_t diagnostic_count, silrig_session **session_out);

#define SILRIG_SESSION_OPEN(names, count, session_out)                                                           \
    silrig_session_open(SILRIG_WIRE_LAYOUT_VERSION, sizeof(silrig_plant_sample_t),                               \
                        sizeof(silrig_command_sample_t), (names), (count), (session_out))

/* The plant's signals. Each waits for the plant's announcement if it has not come yet (SILRIG_ERR_NO_RIG when none
 * comes within twice SILRIG_STARTUP_TIMEOUT_S of opening).
 * silrig_session_signal_index: where the output `name` sits in every sample's outputs[] (input 0), or the input
 * `name` in the command's inputs (input 1): SILRIG_ERR_PLANT, naming the plant's signals, when it has none of that
 * name. Look them up once, after opening: the F-16's outputs are phi_deg, theta_deg, psi_deg, alpha_deg, beta_deg,
 * p_dps, q_dps, r_dps, vt_mps, alt_ft, nz_g, ny_g, aileron_deg, elevator_deg, rudder_deg, throttle and its 13
 * states in book units (vt_fps, alpha_rad, ...); its inputs aileron, elevator, rudder (deg) and throttle (0..1).
 * silrig_session_plant_info: the whole announcement (names, units, input ranges and hold values).
 * silrig_session_held_command: fill inputs_out (the plant's input count) with a command that leaves every input
 * where its actuator is now; set the inputs you command and send the rest as they are. */
int silrig_session_signal_index(silrig_session *session, const char *name, int input, size_t *index_out);
int silrig_session_plant_info(silrig_session *session, silrig_plant_info_t *info_out);
int silrig_session_held_command(silrig_session *session, double *inputs_out, size_t input_count);

/* Block until the next plant sample to answer and copy it to *sample_out (SILRIG_OK). After a stall only the
 * newest waiting sample is handed out. Returns SILRIG_STOPPED (SIGTERM/SIGINT) or SILRIG_RUN_ENDED (the plant
 * has flown the whole scenario) when it is time to close; SILRIG_ERR_NO_RIG if no plant came within twice
 * SILRIG_STARTUP_TIMEOUT_S of opening. While the plant is silent after that (a plant restart), it waits;
 * SILRIG_ERR_PLANT if the restarted plant announces other signals. */
int silrig_session_next_sample(silrig_session *session, silrig_plant_sample_t *sample_out);

/* Answer the sample just handed out: one value per plant input, in the plant's order, and one value per announced
 * diagnostic. The library measures the compute time (sample handed out to this call), stamps the header and
 * validates: NaN, infinity or a value outside its input's range is refused and not sent
 * (SILRIG_ERR_COMMAND_REFUSED; the plant holds the last valid command, the run's events say why).
 * SILRIG_ERR_USAGE: no sample to answer, or an input or diagnostic count other than the plant's or announced. */
int silrig_session_send_command(silrig_session *session, const double *inputs, size_t input_count,
                                const double *diagnostics, size_t diagnostic_count);

/* The controller's step, s (the scenario's dt). */
double silrig_session_dt_s(silrig_session *session);

/* The scenario's attitude set point at the start, deg: roll (phi), pitch (theta), yaw (psi). A scenario whose
 * [[setpoint_steps]] change them later: read silrig_session_setpoint_at each sample instead. */
int silrig_session_setpoint_deg(silrig_session *session, double setpoint_deg_out[3]);

/* The scenario's set point of output `name` ([setpoint] alt_ft = 4000.0) at the start, in that output's unit:
 * SILRIG_OK with *value_out set, SILRIG_NOT_GIVEN when the scenario gives none (phi_deg, theta_deg and psi_deg are
 * always given, 0 by default). The same as silrig_session_setpoint_at at t_s = 0. */
int silrig_session_setpoint(silrig_session *session, const char *name, double *value_out);

/* The set point of output `name` in force at `t_s`, s: pass each sample's t_sim_s. A scenario's [[setpoint_steps]]
 * change set points during the run ({ at_s = 2.0, phi_deg = 10.0 }: from the first tick at or after 2 s); this is
 * the last step at or before t_s that changes `name`, else [setpoint]'s value. Same statuses as
 * silrig_session_setpoint; SILRIG_ERR_USAGE for a NaN t_s. A controller that reads its set points once, at the
 * start, flies a scenario with steps as if it had none. */
int silrig_session_setpoint_at(silrig_session *session, const char *name, double t_s, double *value_out);

/* Checkpoints, so a restarted controller resumes instead of starting cold (copper's Freezable): after a send,
 * when silrig_session_checkpoint_due returns 1, save your state as text with silrig_session_save_checkpoint. A
 * controller the launcher restarts finds that text in silrig_session_restored_checkpoint (NULL otherwise; owned by
 * the session). */
const char *silrig_session_restored_checkpoint(silrig_session *session);
/* Say whether you resumed from the restored checkpoint: used 1, or 0 with a reason (or NULL) saying why it did not
 * fit; the run's events then tell which state the controller joined the flight with. */
int silrig_session_checkpoint_used(silrig_session *session, int used, const char *reason);
int silrig_session_checkpoint_due(silrig_session *session);
int silrig_session_save_checkpoint(silrig_session *session, const char *text);

/* Write the controller's report (<out>/controller.report.json) and free the session. Pass the reason if your
 * controller stops on an error of its own (it goes into the report), else NULL. NULL session: nothing to do. */
int silrig_session_close(silrig_session *session, const char *error);

/* ---- Your own plant (silrig run --plant-cmd): the same library, the plant's side. ----
 * Fill a silrig_plant_info_t with your model's name, outputs (name, unit, OUTPUT_IN_TRACE flag) and inputs (name,
 * unit, min, max, hold: what the failsafe commands; input_held_output: the output that reports the actuator's
 * position, or SILRIG_NO_OUTPUT), open the session, then loop: hand in the outputs at this tick, get the inputs
 * to step the model with over one period. The rig keeps the clock (realtime sleeps or lockstep), the commands and
 * their misses, the watchdog and failsafe, the faults, the logger and the plant's timing report; the model's step
 * time is what passes between silrig_plant_tick calls. */
typedef struct SilrigPlantSession silrig_plant_session;

/* The run's [plant.parameters] value of `name` (numbers only), readable before silrig_plant_open so the model can
 * start (trim) at it and announce its hold values: SILRIG_OK with *value_out set, SILRIG_NOT_GIVEN when the
 * scenario gives none (keep the model's own value), an error when the run's variables or scenario are unusable. */
int silrig_plant_parameter(const char *name, double *value_out);

/* Open the run's plant session (use SILRIG_PLANT_OPEN) and wait up to SILRIG_STARTUP_TIMEOUT_S for the
 * controller and the logger. SILRIG_ERR_PLANT: the announcement breaks a rule (no outputs, a name twice, a name
 * too long, a hold value outside its range, ...), named; or the run has a plant already. */
int silrig_plant_open(uint32_t layout_version, size_t plant_info_size, size_t plant_sample_size,
                      size_t command_sample_size, const silrig_plant_info_t *info,
                      silrig_plant_session **session_out);

#define SILRIG_PLANT_OPEN(info, session_out)                                                                     \
    silrig_plant_open(SILRIG_WIRE_LAYOUT_VERSION, sizeof(silrig_plant_info_t), sizeof(silrig_plant_sample_t),    \
                      sizeof(silrig_command_sample_t), (info), (session_out))

/* Hand in the outputs at this tick (output_count = the announced count) and get the inputs (input_count = the
 * announced count) to step the model with over one period: SILRIG_OK. SILRIG_RUN_ENDED once the scenario's last
 * tick is flown (the outputs of that call close it), SILRIG_STOPPED on SIGTERM/SIGINT: close then. Outputs with
 * NaN or infinity are refused (counted, said in the run's events) and the last valid ones published. */
int silrig_plant_tick(silrig_plant_session *session, const double *outputs, size_t output_count, double *inputs_out,
                      size_t input_count);

/* The run's step, s. */
double silrig_plant_dt_s(silrig_plant_session *session);

/* Checkpoints (realtime), so a restarted plant goes on with the flight instead of flying it again from tick 0:
 * after stepping with the inputs silrig_plant_tick handed out, when silrig_plant_checkpoint_due returns 1, save the
 * model's state as text with silrig_plant_save_checkpoint (the rig adds the tick and its actuators' positions). A
 * plant the launcher restarts finds that text in silrig_plant_restored_checkpoint (NULL otherwise; owned by the
 * session) and says, before its first tick, whether it restored it: used 1 (the flight goes on from the saved
 * tick), or 0 with a reason (or NULL): it flies again from tick 0, as a plant that never answers does. */
const char *silrig_plant_restored_checkpoint(silrig_plant_session *session);
int silrig_plant_checkpoint_used(silrig_plant_session *session, int used, const char *reason);
int silrig_plant_checkpoint_due(silrig_plant_session *session);
int silrig_plant_save_checkpoint(silrig_plant_session *session, const char *text);

/* Write the plant's report (<out>/plant.report.json) and free the session; `error`: why your model gave up, or
 * NULL. */
int silrig_plant_close(silrig_plant_session *session, const char *error);

#ifdef __cplusplus
}
#endif

#endif /* SILRIG_CLIENT_H */
