//! `silrig-logger`: the logger process of the rig. A thin shell over [`silrig::rig::logger::run_logger`].

use clap::Parser;
use std::process::ExitCode;

/// The logger process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-logger", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match silrig::rig::logger::run_logger(&cli.args) {
        Ok(report) if report.ended.starts_with("error") => {
            eprintln!("silrig-logger: {}", report.ended);
            ExitCode::FAILURE
        }
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("silrig-logger: error: {e:#}");
            ExitCode::from(2)
        }
    }
}
