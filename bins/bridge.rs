//! `silrig-bridge`: the rig's streams between the plant's host and a controller's host over Zenoh, and
//! `silrig-bridge keygen` for the key both hosts hold. Parses the arguments and calls the library.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "silrig-bridge",
    version,
    about = "Carry a silrig run's streams to a controller on another host",
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    bridge: silrig::bridge::BridgeOptions,
}

#[derive(Subcommand)]
enum Command {
    /// Write a new bridge key to FILE, readable by its owner only (never over an existing file); copy it to the
    /// other host (scp -p) and give it to both bridges with --key (silrig run: --bridge-key).
    Keygen {
        /// Where to write it.
        file: std::path::PathBuf,
    },
}

fn main() -> ExitCode {
    silrig::rig::owner_only_files();
    let cli = Cli::parse();
    if let Some(Command::Keygen { file }) = &cli.command {
        return match silrig::bridge::key::write_new(file) {
            Ok(key) => {
                eprintln!("silrig-bridge: wrote bridge key {} to {}", key.fingerprint(), file.display());
                ExitCode::SUCCESS
            }
            Err(e) => fail(&e),
        };
    }
    if cli.bridge.check {
        return match silrig::bridge::check(&cli.bridge) {
            Ok(line) => {
                eprintln!("silrig-bridge: {line}");
                ExitCode::SUCCESS
            }
            Err(e) => fail(&e),
        };
    }
    let result = silrig::bridge::run_bridge(&cli.bridge);
    silrig::rig::finish_process("bridge", &cli.bridge.process, result)
}

fn fail(e: &silrig::bridge::BridgeError) -> ExitCode {
    eprintln!("silrig-bridge: error: {e}");
    ExitCode::from(2)
}
