//! Which adapter the rig's processes fly: [`run_plant`] (`silrig-plant`) and [`run_controller`]
//! (`silrig-controller`) read the scenario, name its plant's and controller's kind ([`PlantKind`],
//! [`ControllerKind`]), and hand the adapter of that kind to the rig's process body. A new adapter is one variant
//! of a kind and one arm of its match.

use crate::builtin::attitude_law::AttitudeLaw;
use crate::builtin::f16_plant::F16Plant;
use crate::builtin::quad_law::QuadLaw;
use crate::builtin::quad_plant::QuadPlant;
use crate::fmu::controller::run_fmu_controller;
use crate::fmu::plant::{FmuPlant, run_fmu_plant};
use crate::udp::device::run_device_controller;
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_rig::ProcessArgs;
use silrig_rig::controller::{Controller, serve};
use silrig_rig::plant::run_plant_model;
use silrig_rig::report::ProcessReport;
use std::path::{Path, PathBuf};

/// What flies as the plant.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PlantKind {
    /// The built-in F-16 (a scenario without `[plant] fmu` or `[plant] model`).
    F16,
    /// The built-in X quadrotor (`[plant] model = "quad"`).
    Quad,
    /// A co-simulation FMU (`[plant] fmu`).
    Fmu(PathBuf),
}

impl PlantKind {
    /// The kind of plant `scenario` flies.
    pub fn of(scenario: &Scenario) -> Self {
        match &scenario.plant.fmu {
            Some(path) => Self::Fmu(path.clone()),
            None if silrig_flight::quad::is_quad(scenario) => Self::Quad,
            None => Self::F16,
        }
    }
}

/// What flies as the controller.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ControllerKind {
    /// Ours for the F-16, the paper's adaptive SMC/RBF law (a scenario without `[controller] fmu`).
    AttitudeLaw,
    /// Ours for the quadrotor, cascaded attitude and rate loops with a mixer.
    QuadLaw,
    /// A co-simulation FMU (`[controller] fmu`).
    Fmu(PathBuf),
    /// A device over UDP (`[controller] device`, its packet layout file): flight software in the loop.
    Device(PathBuf),
}

impl ControllerKind {
    /// The kind of controller `scenario` names, or ours for its built-in vehicle; for a plant FMU with no
    /// controller named, [`ControllerKind::fitting`] chooses.
    pub fn of(scenario: &Scenario) -> Self {
        if let Some(layout) = &scenario.controller.device {
            return Self::Device(layout.clone());
        }
        match &scenario.controller.fmu {
            Some(path) => Self::Fmu(path.clone()),
            None if silrig_flight::quad::is_quad(scenario) => Self::QuadLaw,
            None => Self::AttitudeLaw,
        }
    }

    /// The kind of controller `scenario` flies: the one it names (an FMU, a device), or ours for its built-in
    /// vehicle; for a plant FMU with none named, our law that connects to the FMU's signals (`plant_fmu_signals`,
    /// read only then): the quadrotor's for the quadrotor's FMU, the F-16's for the F-16's. None fitting, the
    /// error names the plant's signals and how to name its controller.
    pub fn fitting(
        scenario: &Scenario,
        plant_fmu_signals: impl FnOnce(&Path) -> anyhow::Result<PlantSignals>,
    ) -> anyhow::Result<Self> {
        let named = Self::of(scenario);
        let Some(fmu) = &scenario.plant.fmu else { return Ok(named) };
        if scenario.controller.fmu.is_some() || scenario.controller.device.is_some() {
            return Ok(named);
        }
        let plant = plant_fmu_signals(fmu)?;
        let f16 = AttitudeLaw::new(scenario).connect(&plant);
        let quad = QuadLaw::new(scenario).and_then(|mut law| law.connect(&plant));
        match (f16, quad) {
            (Ok(()), _) => Ok(Self::AttitudeLaw),
            (_, Ok(())) => Ok(Self::QuadLaw),
            (Err(f16), Err(quad)) => Err(anyhow::anyhow!(fits_no_law(&plant, &f16, &quad))),
        }
    }
}

/// Why no built-in law flies this plant: what each missed, the plant's signals, and how to name a controller.
fn fits_no_law(plant: &PlantSignals, f16: &str, quad: &str) -> String {
    // A law's refusal names the signal it missed, then lists the plant's, which are said once below.
    let missed = |why: &str| why.split_once("; its ").map_or(why, |(first, _)| first).to_string();
    let outputs: Vec<&str> = plant.outputs.iter().map(|o| o.name.as_str()).collect();
    let inputs: Vec<&str> = plant.inputs.iter().map(|i| i.name.as_str()).collect();
    format!(
        "the plant FMU {} fits no built-in controller (ours for the F-16: {}; ours for the quadrotor: {}); its \
         outputs: {}; its inputs: {}. Name the controller that flies it: `--controller-fmu FILE` (or `[controller] \
         fmu` in the scenario), or, with `silrig run` and `silrig check`, `--controller-cmd CMD` or \
         `--controller external`",
        plant.plant,
        missed(f16),
        missed(quad),
        outputs.join(", "),
        inputs.join(", "),
    )
}

/// Run the plant process to the end of the scenario (or SIGTERM) and write its report.
pub fn run_plant(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    silrig_rig::signals::install_termination_flag();
    let scenario = args.scenario()?;
    match PlantKind::of(&scenario) {
        PlantKind::F16 => {
            let model = Box::new(F16Plant::new(&scenario)?);
            run_plant_model(args, scenario, model)
        }
        PlantKind::Quad => {
            let model = Box::new(QuadPlant::new(&scenario)?);
            run_plant_model(args, scenario, model)
        }
        PlantKind::Fmu(path) => run_fmu_plant(args, scenario, &path),
    }
}

/// Run the controller process until the run ends (or SIGTERM) and write its report.
pub fn run_controller(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    let kind = ControllerKind::fitting(&scenario, |fmu| Ok(FmuPlant::check(fmu, &scenario)?.signals))?;
    match kind {
        ControllerKind::AttitudeLaw => {
            let law = Box::new(AttitudeLaw::new(&scenario));
            serve(args, scenario, law)
        }
        ControllerKind::QuadLaw => {
            let law = QuadLaw::new(&scenario).map_err(|e| anyhow::anyhow!("the scenario: {e}"))?;
            serve(args, scenario, Box::new(law))
        }
        ControllerKind::Fmu(path) => run_fmu_controller(args, scenario, &path),
        ControllerKind::Device(layout) => run_device_controller(args, &layout),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scenario_names_the_kind_of_plant_and_controller() {
        let mut scenario = Scenario::embedded_default();
        assert_eq!(PlantKind::of(&scenario), PlantKind::F16);
        assert_eq!(ControllerKind::of(&scenario), ControllerKind::AttitudeLaw);
        scenario.plant.fmu = Some("airframe.fmu".into());
        scenario.controller.fmu = Some("pid.fmu".into());
        assert_eq!(PlantKind::of(&scenario), PlantKind::Fmu("airframe.fmu".into()));
        assert_eq!(ControllerKind::of(&scenario), ControllerKind::Fmu("pid.fmu".into()));
    }

    #[test]
    fn a_plant_fmu_with_no_controller_named_gets_the_law_that_fits_its_signals() {
        let mut scenario = Scenario::embedded_any_plant();
        let quad = Scenario::from_toml(
            "name = \"q\"\n[plant]\nmodel = \"quad\"\n[timing]\ndt_s = 0.001\nduration_s = 1.0\ncommand_timing = \"next-tick\"\n",
            "test",
        )
        .unwrap();
        let quad_signals = silrig_flight::quad::builtin_signals(&quad).unwrap();
        let f16_signals = silrig_flight::f16_signals::f16_signals([0.0; 4]);
        // Not a plant FMU: the FMU's signals are never read.
        let unread = |_: &Path| -> anyhow::Result<PlantSignals> { panic!("read") };
        assert_eq!(ControllerKind::fitting(&scenario, unread).unwrap(), ControllerKind::AttitudeLaw);
        scenario.plant.fmu = Some("plant.fmu".into());
        let fit = |signals: &PlantSignals| ControllerKind::fitting(&scenario, |_| Ok(signals.clone()));
        assert_eq!(fit(&quad_signals).unwrap(), ControllerKind::QuadLaw);
        assert_eq!(fit(&f16_signals).unwrap(), ControllerKind::AttitudeLaw);
        let mut toy = quad_signals.clone();
        toy.plant = "toy".into();
        toy.outputs.retain(|o| o.name != "alt_m");
        let refused = fit(&toy).unwrap_err().to_string();
        assert!(
            refused.starts_with(
                "the plant FMU toy fits no built-in controller (ours for the F-16: plant toy has no output \
                 `vt_fps`; ours for the quadrotor: plant toy has no output `alt_m`); its outputs: phi_deg, theta_deg"
            ),
            "{refused}"
        );
        assert!(refused.contains("its inputs: motor1, motor2, motor3, motor4. Name the controller"), "{refused}");
        scenario.controller.fmu = Some("pid.fmu".into());
        assert_eq!(ControllerKind::fitting(&scenario, unread).unwrap(), ControllerKind::Fmu("pid.fmu".into()));
    }
}
