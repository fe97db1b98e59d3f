//! `silrig-controller` and the Rust face of the controller session. A [`Controller`] is the control law alone (one
//! step per plant sample, its diagnostics' names, optional checkpoint and restore, as copper's `Freezable`);
//! [`serve`] flies it in a [`ControllerSession`] (`super::session`), which owns everything around it: the streams,
//! the announcement, the in-loop faults, the bumpless blend after a restart, checkpoint files and the report. A
//! controller in another language gets the same session through the C ABI of `libsilrig_client.so`. Our controller
//! is [`AttitudeLaw`], the same [`silrig_model::control::AttitudeController`] as `silrig sim`, served by
//! [`run_controller`].
//!
//! With a fault plan the session asks for the controller's checkpoint every few ticks; restarted with `--resume`,
//! ours restores its RBF weights, so it need not re-learn them.

use super::ProcessArgs;
use super::plant::snapshot;
use super::report::ProcessReport;
pub use super::session::ControlCommand;
use super::session::{ControllerSession, Next, SessionError};
use silrig_flight::scenario::Scenario;
use silrig_flight::sim::{measurement, setpoint_rad, write_attitude_diagnostics};
use silrig_model::control::AttitudeController;
use silrig_wire::wire::PlantSample;

/// A controller the rig can fly. The session around it ([`serve`], over [`ControllerSession`]) owns everything
/// else: the transport, the clock, the in-loop faults, the bumpless blend when it joins a flying plant, checkpoint
/// files, and the report.
pub trait Controller {
    /// Names of the diagnostics [`Controller::step`] reports, in order (announced once per epoch; at most
    /// [`silrig_wire::wire::MAX_DIAGNOSTICS`], see [`silrig_wire::wire::ControllerInfo::new`] for the characters
    /// allowed).
    fn diagnostic_names(&self) -> Vec<String>;

    /// The command for one plant sample; write the diagnostics of this step into `diagnostics` (one per name).
    fn step(&mut self, sample: &PlantSample, dt_s: f64, diagnostics: &mut [f64]) -> ControlCommand;

    /// The state a restarted controller should resume from, as text (`None`: nothing worth saving).
    fn checkpoint(&self) -> Option<String> {
        None
    }

    /// Resume from what [`Controller::checkpoint`] saved; an error (why it does not fit) leaves the controller
    /// as it was, and the run's events say the controller started fresh and why.
    fn restore(&mut self, _saved: &str) -> Result<(), String> {
        Err("this controller keeps no state to resume".into())
    }
}

/// The paper's adaptive SMC/RBF controller behind the [`Controller`] trait; its checkpoint is its RBF weights.
pub struct AttitudeLaw {
    controller: AttitudeController,
    setpoint: [f64; 3],
}

impl AttitudeLaw {
    /// The scenario's controller, with zero weights.
    pub fn new(scenario: &Scenario) -> Self {
        let tables = silrig_model::plant::F16Model::new(scenario.plant.xcg).tables();
        Self {
            controller: AttitudeController::new(scenario.controller.clone(), tables),
            setpoint: setpoint_rad(scenario),
        }
    }
}

impl Controller for AttitudeLaw {
    fn diagnostic_names(&self) -> Vec<String> {
        silrig_flight::trace::attitude_diagnostic_names(self.controller.gains().rbf.nodes())
    }

    fn step(&mut self, sample: &PlantSample, dt_s: f64, diagnostics: &mut [f64]) -> ControlCommand {
        let (command, diag) = self.controller.step(&measurement(&snapshot(sample)), &self.setpoint, dt_s);
        write_attitude_diagnostics(diagnostics, &diag, &self.controller);
        ControlCommand {
            surface_cmd_deg: [command.aileron_deg, command.elevator_deg, command.rudder_deg],
            throttle_cmd: sample.throttle,
        }
    }

    fn checkpoint(&self) -> Option<String> {
        let weights: [&Vec<f64>; 3] = std::array::from_fn(|c| &self.controller.networks()[c].weights);
        serde_json::to_string(&weights).ok()
    }

    fn restore(&mut self, saved: &str) -> Result<(), String> {
        let weights =
            serde_json::from_str::<[Vec<f64>; 3]>(saved).map_err(|e| format!("not three lists of RBF weights: {e}"))?;
        self.controller.set_weights(&weights)
    }
}

/// Serve `law` as the run's controller until the run ends or SIGTERM, and write the report: one
/// [`ControllerSession`] with the law plugged in. An error that stopped the loop is returned after the report is
/// written.
pub fn serve(args: &ProcessArgs, scenario: Scenario, mut law: Box<dyn Controller>) -> anyhow::Result<ProcessReport> {
    let names = law.diagnostic_names();
    let mut session = ControllerSession::open(args.clone(), scenario, &names)?;
    if let Some(saved) = session.restored_checkpoint().map(str::to_owned) {
        session.checkpoint_used(law.restore(&saved));
    }
    let dt_s = session.dt_s();
    let mut diagnostics = vec![0.0; names.len()];
    let error = loop {
        let sample = match session.next_sample() {
            Ok(Next::Sample(sample)) => sample,
            Ok(Next::Stop(_)) => break None,
            Err(e) => break Some(e),
        };
        let command = law.step(&sample, dt_s, &mut diagnostics);
        match session.send(&command, &diagnostics) {
            // Refused: the session said why in the run's events and the plant holds; the next sample may do.
            Ok(()) | Err(SessionError::CommandRefused { .. }) => {}
            Err(e) => break Some(e),
        }
        if session.checkpoint_due()
            && let Some(text) = law.checkpoint()
        {
            session.save_checkpoint(&text);
        }
    };
    if let Some(e) = &error {
        session.fail(e);
    }
    let report = session.finish()?;
    match error {
        Some(e) => Err(e.into()),
        None => Ok(report),
    }
}

/// Run our controller (the paper's, from the scenario) until SIGTERM and write its report.
pub fn run_controller(args: &ProcessArgs) -> anyhow::Result<ProcessReport> {
    let scenario = args.scenario()?;
    let law = AttitudeLaw::new(&scenario);
    serve(args, scenario, Box::new(law))
}
