//! The Rust face of the controller session. A [`Controller`] is the control law alone (the plant's signals it
//! reads and commands, found by name once; one step per plant sample; its diagnostics' names; optional checkpoint
//! and restore, as copper's `Freezable`); [`serve`] flies it in a [`ControllerSession`] (`super::session`), which
//! owns everything around it: the streams, the announcement, the in-loop faults, the bumpless blend after a
//! restart, checkpoint files and the report. A controller in another language gets the same session through the C
//! ABI of `libsilrig_client.so`. Which controller `silrig-controller` serves (ours, a controller FMU) is the
//! adapters' choice (`silrig-adapters`), not the rig's.
//!
//! With a fault plan the session asks for the controller's checkpoint every few ticks and hands a restarted
//! controller (`--resume`) what it saved.

use super::ProcessArgs;
pub use super::report::ControllerFigures;
use super::report::ProcessReport;
use super::session::{ControllerSession, Next, SessionError};
use silrig_flight::scenario::Scenario;
use silrig_flight::signals::PlantSignals;
use silrig_wire::wire::PlantSample;

/// A controller the rig can fly. The session around it ([`serve`], over [`ControllerSession`]) owns everything
/// else: the transport, the clock, the in-loop faults, the bumpless blend when it joins a flying plant, checkpoint
/// files, and the report.
pub trait Controller {
    /// Names of the diagnostics [`Controller::step`] reports, in order (announced once per epoch; at most
    /// [`silrig_wire::wire::MAX_DIAGNOSTICS`], see [`silrig_wire::wire::ControllerInfo::new`] for the characters
    /// allowed).
    fn diagnostic_names(&self) -> Vec<String>;

    /// Find the outputs it reads and the inputs it commands in the plant's announcement, by name, before the first
    /// step; an error (naming what is missing, [`PlantSignals::output`]) ends the session.
    fn connect(&mut self, plant: &PlantSignals) -> Result<(), String>;

    /// The command for one plant sample: `command` holds one value per plant input, each where its actuator is now
    /// (an input left alone stays there); write the diagnostics of this step into `diagnostics` (one per name).
    fn step(&mut self, sample: &PlantSample, dt_s: f64, command: &mut [f64], diagnostics: &mut [f64]);

    /// Why the controller cannot go on after its last step (an FMU's failed call), asked after every step: `Some`
    /// ends the session with that error, and that step's command is not sent.
    fn failure(&mut self) -> Option<String> {
        None
    }

    /// Whether the controller has no command for the sample it just stepped (a device of its own is down): none is
    /// sent, and the plant holds the last one and then flies its failsafe, as for any silent controller. Realtime
    /// only: in lockstep the plant waits for every command.
    fn withholds(&self) -> bool {
        false
    }

    /// The state a restarted controller should resume from, as text (`None`: nothing worth saving).
    fn checkpoint(&self) -> Option<String> {
        None
    }

    /// Resume from what [`Controller::checkpoint`] saved; an error (why it does not fit) leaves the controller
    /// as it was, and the run's events say the controller started fresh and why.
    fn restore(&mut self, _saved: &str) -> Result<(), String> {
        Err("this controller keeps no state to resume".into())
    }

    /// Figures of its own for the controller's report, asked once at the end of the session (a device's link round
    /// trip beside the rig's own distributions, its refused packets beside the rig's counters).
    fn figures(&self) -> ControllerFigures {
        ControllerFigures::default()
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
    let mut connected = false;
    let error = loop {
        let sample = match session.next_sample() {
            Ok(Next::Sample(sample)) => sample,
            Ok(Next::Stop(_)) => break None,
            Err(e) => break Some(e.into()),
        };
        if !std::mem::replace(&mut connected, true)
            && let Err(e) = law.connect(session.plant()?)
        {
            break Some(SessionError::Plant(e).into());
        }
        let mut command = session.held_command();
        law.step(&sample, dt_s, &mut command, &mut diagnostics);
        if let Some(why) = law.failure() {
            break Some(anyhow::anyhow!(why));
        }
        if law.withholds() {
            continue;
        }
        match session.send(&command, &diagnostics) {
            // Refused: the session said why in the run's events and the plant holds; the next sample may do.
            Ok(()) | Err(SessionError::CommandRefused { .. }) => {}
            Err(e) => break Some(e.into()),
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
    session.add_figures(law.figures());
    let report = session.finish()?;
    match error {
        Some(e) => Err(e),
        None => Ok(report),
    }
}
