//! silrig-launch: `silrig run`, the launcher that starts the rig's processes, supervises and restarts them, applies
//! the fault plan and writes the run's report.
//!
//! - [`launcher`]: `silrig run` from options to report, in phases; [`options`]: what it is asked to do; `prepare`:
//!   phase 1, the options, the scenario and its FMUs checked and the run's folder and id claimed; [`supervision`]:
//!   the processes, their lives and restarts; [`child`]: one child process, started, its output logged, reaped
//!   once; `joining`: who has joined the run, and a role that never did; [`program`]: finding the binaries and
//!   splitting a user's command; [`claim`]: run ids and the locks that claim a run's folder and id;
//!   [`process_env`]: the run's variables for a process started by hand.
//! - [`fault_schedule`]: carrying out process faults (signals) on time; [`fault_report`]: what each fault did.
//! - [`run_report`]: `report.json` and the timing tables; [`run_figures`]: the run's figures, or why one is left out; [`floor`]: the OS timer floor measured
//!   beside a run (ours and cyclictest's); [`held_outputs`]: the ticks a degraded plant held, flagged and judged.
//! - [`warm`]: a sweep's warm rig, whose warm processes fork each case's processes.
//! - [`remote`]: the plant-side bridge for a controller on another host.
//!
//! Layers: uses `silrig-rig` (the processes it starts), `silrig-plot`, `silrig-recording`, `silrig-wire` and
//! `silrig-flight`.

pub mod child;
pub mod claim;
pub mod fault_report;
pub mod fault_schedule;
pub mod floor;
pub mod held_outputs;
mod joining;
pub mod launcher;
pub mod options;
mod prepare;
pub mod process_env;
pub mod program;
pub mod remote;
pub mod run_figures;
pub mod run_report;
pub mod supervision;
pub mod warm;
