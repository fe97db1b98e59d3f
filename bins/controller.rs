//! `silrig-controller`: the controller process of the rig. A thin shell over [`silrig::rig::controller_process::run_controller`]
//! (ours, or the scenario's controller FMU), or [`silrig::adapters::udp::device::run_device_controller`] for a
//! scenario whose controller is a device over UDP (the adapters sit above the rig, so the choice is made here).

use clap::Parser;

/// The controller process of a silrig run (normally started by `silrig run`).
#[derive(Parser)]
#[command(name = "silrig-controller", version)]
struct Cli {
    #[command(flatten)]
    args: silrig::rig::ProcessArgs,
}

fn main() -> std::process::ExitCode {
    silrig::rig::owner_only_files();
    let cli = Cli::parse();
    let run = match cli.args.scenario().map(|s| s.controller.device.clone()) {
        Ok(Some(layout)) => silrig::adapters::udp::device::run_device_controller(&cli.args, &layout),
        _ => silrig::rig::controller_process::run_controller(&cli.args),
    };
    silrig::rig::finish_process("controller", &cli.args, run)
}
