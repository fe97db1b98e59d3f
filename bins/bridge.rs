//! `silrig-bridge`: the rig's streams between the plant's host and a controller's host over Zenoh. Parses the
//! arguments and calls the library.

use clap::Parser;

#[derive(Parser)]
#[command(name = "silrig-bridge", version, about = "Carry a silrig run's streams to a controller on another host")]
struct Cli {
    #[command(flatten)]
    bridge: silrig::bridge::BridgeOptions,
}

fn main() -> std::process::ExitCode {
    silrig::rig::owner_only_files();
    let cli = Cli::parse();
    let result = silrig::bridge::run_bridge(&cli.bridge);
    silrig::rig::finish_process("bridge", &cli.bridge.process, result)
}
