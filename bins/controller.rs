//! `silrig-controller`: the controller process of the rig. A thin shell over
//! [`silrig::adapters::process::run_controller`] (ours, or the scenario's controller FMU).

use clap::Parser;

/// The controller process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-controller", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
}

fn main() -> std::process::ExitCode {
    silrig::rig::owner_only_files();
    // In a sweep's warm rig this process forks one flight after another; each returns here with its arguments.
    let cli = match silrig::rig::warm::serve_flights() {
        Some(argv) => Cli::parse_from(argv),
        None => Cli::parse(),
    };
    silrig::rig::finish_process("controller", &cli.args, silrig::adapters::process::run_controller(&cli.args))
}
