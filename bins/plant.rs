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
    let cli = Cli::parse();
    silrig::rig::finish_process("plant", &cli.args, silrig::adapters::process::run_plant(&cli.args))
}
