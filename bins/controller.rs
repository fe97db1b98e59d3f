//! `silrig-controller`: the controller process of the rig. A thin shell over [`silrig::rig::controller::run_controller`].

use clap::Parser;
use std::process::ExitCode;

/// The controller process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-controller", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match silrig::rig::controller::run_controller(&cli.args) {
        Ok(report) if report.ended.starts_with("error") => {
            eprintln!("silrig-controller: {}", report.ended);
            ExitCode::FAILURE
        }
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("silrig-controller: error: {e:#}");
            ExitCode::from(2)
        }
    }
}
