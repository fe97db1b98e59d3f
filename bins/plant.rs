//! `silrig-plant`: the plant process of the rig. A thin shell over [`silrig::rig::plant::run_plant`].

use clap::Parser;
use std::process::ExitCode;

/// The plant process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-plant", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match silrig::rig::plant::run_plant(&cli.args) {
        Ok(report) if report.ended.starts_with("error") => {
            eprintln!("silrig-plant: {}", report.ended);
            ExitCode::FAILURE
        }
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("silrig-plant: error: {e:#}");
            ExitCode::from(2)
        }
    }
}
