//! `silrig-bridge`: the rig's streams between the plant's host and a controller's host over Zenoh, and
//! `silrig-bridge keygen` for the key both hosts hold. Parses the arguments and calls the library.

use clap::Parser;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "silrig-bridge",
    version,
    about = "Carry a silrig run's streams to a controller on another host",
    after_help = "The bridge key both hosts hold: `silrig-bridge keygen FILE` (see `silrig-bridge keygen --help`)."
)]
struct Cli {
    #[command(flatten)]
    bridge: silrig::bridge::BridgeOptions,
}

/// A subcommand of its own words: the bridge's flags (a required run id among them) have nothing to do with it.
#[derive(Parser)]
#[command(
    name = "silrig-bridge keygen",
    version,
    about = "Write a new bridge key to FILE, readable by its owner only (never over an existing file); copy it to the \
             other host (scp -p) and give it to both bridges with --key (silrig run --bridge-key)"
)]
struct Keygen {
    /// Where to write it.
    file: std::path::PathBuf,
}

fn main() -> ExitCode {
    silrig::rig::owner_only_files();
    if std::env::args().nth(1).as_deref() == Some("keygen") {
        // Named as typed in its usage line, not as `keygen`.
        let args = std::iter::once("silrig-bridge keygen".to_string()).chain(std::env::args().skip(2));
        let Keygen { file } = Keygen::parse_from(args);
        return match silrig::bridge::key::write_new(&file) {
            Ok(key) => {
                eprintln!("silrig-bridge: wrote bridge key {} to {}", key.fingerprint(), file.display());
                ExitCode::SUCCESS
            }
            Err(e) => fail(&e),
        };
    }
    let cli = Cli::parse();
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
