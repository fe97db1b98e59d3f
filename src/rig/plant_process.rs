//! What `silrig-plant` flies: the scenario's FMU when it names one ([`super::fmu_plant`]), else the built-in F-16
//! ([`super::plant`]).

use super::ProcessArgs;
use super::report::ProcessReport;

/// Run the plant process to the end of the scenario (or SIGTERM) and write its report.
pub fn run_plant(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    super::signals::install_termination_flag();
    let scenario = args.scenario()?;
    match scenario.plant.fmu.clone() {
        Some(fmu) => super::fmu_plant::run_fmu_plant(args, scenario, &fmu),
        None => super::plant::run_f16_plant(args, scenario),
    }
}
