//! What `silrig-plant` flies: the scenario's FMU when it names one ([`super::fmu_plant`]), else the built-in vehicle
//! it names (`[plant] model`: the quadrotor, [`super::quad_plant`]; the F-16, [`super::f16_plant`]) in
//! [`super::plant`]'s loop.

use super::ProcessArgs;
use super::report::ProcessReport;

/// Run the plant process to the end of the scenario (or SIGTERM) and write its report.
pub fn run_plant(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    super::signals::install_termination_flag();
    let scenario = args.scenario()?;
    match scenario.plant.fmu.clone() {
        Some(fmu) => super::fmu_plant::run_fmu_plant(args, scenario, &fmu),
        None if silrig_flight::quad::is_quad(&scenario) => super::quad_plant::run_quad_plant(args, scenario),
        None => {
            let model = Box::new(super::f16_plant::F16Plant::new(&scenario)?);
            super::plant::run_model_plant(args, scenario, model)
        }
    }
}
