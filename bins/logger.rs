//! `silrig-logger`: the logger process of the rig. A thin shell over [`silrig::rig::logger::run_logger`].

use clap::Parser;

/// The logger process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-logger", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
}

fn main() -> std::process::ExitCode {
    silrig::rig::owner_only_files();
    let cli = Cli::parse();
    silrig::rig::finish_process("logger", &cli.args, silrig::rig::logger::run_logger(&cli.args))
}
