//! What `silrig-controller` flies: the scenario's controller FMU when it names one ([`super::fmu_controller`]),
//! else ours for the vehicle it flies (the quadrotor's, [`super::quad_law`]; the F-16's, [`super::controller`]).
//! Decided here, not in `controller`, which the FMU controller builds on.

use super::ProcessArgs;
use super::report::ProcessReport;

/// Run the controller process until the run ends (or SIGTERM) and write its report.
pub fn run_controller(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    match scenario.controller.fmu.clone() {
        Some(fmu) => super::fmu_controller::run_fmu_controller(args, scenario, &fmu),
        None if silrig_flight::quad::is_quad(&scenario) => super::quad_law::run_quad_controller(args, scenario),
        None => super::controller::run_controller(args),
    }
}
