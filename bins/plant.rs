//! `silrig-plant`: the plant process of the rig. A thin shell over [`silrig::adapters::process::run_plant`].

use clap::Parser;

/// The plant process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-plant", version)]
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
    silrig::rig::finish_process("plant", &cli.args, silrig::adapters::process::run_plant(&cli.args))
}
