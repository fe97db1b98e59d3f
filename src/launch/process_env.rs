//! The run's variables for a process the launcher does not start itself (`--controller external`, `--plant
//! external`, a bridged controller): written as `<out>/<role>.env` with how to start one, and the wait for such a
//! process's report when the run ends.

use crate::supervision::ControllerLaunch;
use anyhow::Context;
use silrig_flight::role::Role;
use silrig_rig::ProcessArgs;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// `<out>/<name>`: the run's variables as `export NAME='value'` lines, written whole or not at all (someone waiting for
/// the file to appear sources it at once).
fn write_env_file(args: &ProcessArgs, name: &str) -> anyhow::Result<PathBuf> {
    let lines: String =
        args.to_env().iter().map(|(k, v)| format!("export {k}='{}'\n", v.replace('\'', "'\\''"))).collect();
    let path = args.out.join(name);
    silrig_flight::files::write_atomically(&path, &lines).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

/// `<out>/controller.env`: the variables a controller of this run reads (`export NAME='value'` lines, for `.` in a
/// shell); for `--controller external` also printed with how to start it.
pub(crate) fn write_controller_env(
    args: &ProcessArgs,
    controller: &ControllerLaunch,
    remote: bool,
) -> anyhow::Result<()> {
    let path = write_env_file(args, "controller.env")?;
    if *controller == ControllerLaunch::External && !remote {
        eprintln!(
            "silrig run: waiting up to {} s for a controller on run {}; start yours with the run's variables, e.g.\n  \
             . {} && python3 examples/python/pid_attitude.py",
            args.options.startup_timeout_s,
            args.run_id,
            path.display()
        );
    }
    Ok(())
}

/// `<out>/plant.env` for `--plant external`: the same variables, printed with how to start a plant.
pub(crate) fn write_plant_env(args: &ProcessArgs) -> anyhow::Result<()> {
    let path = write_env_file(args, "plant.env")?;
    eprintln!(
        "silrig run: waiting up to {} s for a plant on run {}; start yours with the run's variables, e.g.\n  \
         . {} && python3 tests/clients/toy_plant.py",
        args.options.startup_timeout_s,
        args.run_id,
        path.display()
    );
    Ok(())
}

/// A process the launcher did not start writes its report when it sees the run end; give it a moment.
pub(crate) fn wait_for_external_report(out: &Path, role: Role) {
    let path = silrig_rig::report::report_path(out, role.label());
    let deadline = std::time::Instant::now() + Duration::from_secs(5);
    while !path.exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
}
