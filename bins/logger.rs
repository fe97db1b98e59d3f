//! `silrig-logger`: the logger process of the rig. A thin shell over [`silrig::rig::logger::run_logger`].

use clap::Parser;

/// The logger process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-logger", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
    /// Also serve the recording's channels, as they are written, over the Foxglove WebSocket protocol on IP:PORT
    /// (`silrig run --live foxglove`; needs the `live` feature).
    #[arg(long, value_name = "IP:PORT")]
    live_foxglove: Option<std::net::SocketAddr>,
}

fn main() -> std::process::ExitCode {
    silrig::rig::owner_only_files();
    // In a sweep's warm rig this process forks one flight after another; each returns here with its arguments.
    let cli = match silrig::rig::warm::serve_flights() {
        Some(argv) => Cli::parse_from(argv),
        None => Cli::parse(),
    };
    silrig::rig::finish_process("logger", &cli.args, silrig::rig::logger::run_logger(&cli.args, cli.live_foxglove))
}
