//! Who has joined the run: a role's process has joined once a node of the run's iceoryx2 namespace belongs to it
//! (its pid, or for a user's command a process of the group it leads). One that has not within the start-up
//! timeout, or that exits first, is the run's culprit, said in words that name the role, its command, how long it
//! was waited for and what to check; the peers that gave up waiting for it are not.

use crate::child::ChildProcess;
use silrig_flight::role::Role;
use silrig_wire::ipc::{NodeOfRun, RunId};
use std::time::{Duration, Instant};

/// A role's process as the join watch sees it: whether it has joined the run yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Joining {
    /// Started, no node of its own seen yet.
    Waited { since: Instant },
    /// A node of the run belongs to it.
    Joined,
    /// It did not join within the start-up timeout: the run was stopped for it.
    NeverJoined,
    /// A restart, not watched: the run flies on while it joins, and the fault plan may hold it stopped meanwhile.
    Restarted,
}

impl Joining {
    /// A process just started, after `restarts` restarts of its role: the first life is watched.
    pub(crate) fn started(restarts: u32) -> Self {
        if restarts == 0 { Self::Waited { since: Instant::now() } } else { Self::Restarted }
    }
}

/// Whether one of `nodes` belongs to `process`. Alive nodes count whoever holds them; a dead node (its process
/// ended without closing it) counts for the child itself, whose pid cannot have been reused before it is reaped.
pub(crate) fn has_joined(process: &ChildProcess, nodes: &[NodeOfRun]) -> bool {
    nodes.iter().any(|n| if n.alive { process.owns(n.pid) } else { n.pid == i64::from(process.pid()) })
}

/// Wait until `process` has a node of `run_id` alive, has ended, or `within` has passed: what the launcher waits
/// for before it starts the next role's process, because concurrent node creation with iceoryx2's dead-node
/// cleanup is where iceoryx2 has had races (#1880: a node still being created can look dead to another process
/// creating its own). A fixed pause of `within` between starts did the same at a cost every run pays (40 ms of a
/// sweep case's 110); a process forked warm or written in C has its node within a few milliseconds.
pub(crate) fn wait_until_joined(process: &mut ChildProcess, run_id: &RunId, within: Duration) {
    let start = Instant::now();
    while start.elapsed() < within {
        let alive = nodes(run_id).iter().any(|n| n.alive && process.owns(n.pid));
        if alive || !matches!(process.poll(), Ok(None)) {
            return;
        }
        std::thread::sleep(Duration::from_micros(500));
    }
}

/// The nodes of the run, or none when they cannot be listed right now (a node being created as it looks): the next
/// look sees them.
pub(crate) fn nodes(run_id: &RunId) -> Vec<NodeOfRun> {
    silrig_wire::ipc::nodes_of_run(run_id).unwrap_or_default()
}

/// Who a role's process is, for a person: the user's command with its flag, or the rig's binary.
pub(crate) fn who(role: Role, command: Option<&str>, pid: u32) -> String {
    match command {
        Some(cmd) => format!("your --{role}-cmd `{cmd}` (pid {pid})"),
        None => format!("{} (pid {pid})", role.binary()),
    }
}

/// What a role's process must do to join, and where the book says how.
fn how_to_join(role: Role, command: bool) -> String {
    if !command {
        return format!(
            "see {role}.stderr.log in the run's folder for what held it up, and rebuild the binaries with `cargo \
             build --release`"
        );
    }
    let (session, python, guide) = match role {
        Role::Plant => ("plant", "silrig_client.serve_plant", "Bring your own plant"),
        _ => ("controller", "silrig_client.serve", "Fly your controller"),
    };
    format!(
        "check that it opens a {session} session of silrig's session library (libsilrig_client.so, which the \
         launcher names in SILRIG_CLIENT_LIB; in Python {python} or the silrig package) with the run's SILRIG_* \
         variables from its environment, or, speaking the contract itself, that it creates its iceoryx2 node with \
         the run's config (SILRIG_RUN_ID) and publishes the run's services (the book: {guide}; `silrig contract`)"
    )
}

/// The run's first failure when a role's process is still running but never joined within `waited_s`.
pub(crate) fn never_joined(role: Role, who: &str, command: bool, run_id: &RunId, waited_s: f64) -> String {
    format!(
        "{role}: {who} never joined run `{run_id}`: no node of its own after {waited_s:.1} s \
         (--startup-timeout-s), so the run was stopped; {}",
        how_to_join(role, command)
    )
}

/// The failure of a role's process that ended before it joined the run: its exit status, when, and the end of
/// its stderr (`tail`, from [`crate::supervision::stderr_tail`]).
pub(crate) fn exited_before_joining(role: Role, who: &str, how: &str, after_s: f64, tail: &str) -> String {
    format!("{role}: {who} ended before it joined the run ({how}, {after_s:.1} s after it started){tail}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_role_that_never_joins_is_named_with_its_command_the_time_waited_and_what_to_check() {
        let run = RunId::new("r1").unwrap();
        let who = who(Role::Plant, Some("sleep 100"), 42);
        let text = never_joined(Role::Plant, &who, true, &run, 2.0);
        assert!(text.starts_with("plant: your --plant-cmd `sleep 100` (pid 42) never joined run `r1`"), "{text}");
        assert!(text.contains("after 2.0 s (--startup-timeout-s)") && text.contains("serve_plant"), "{text}");
        let ours = never_joined(Role::Controller, &super::who(Role::Controller, None, 7), false, &run, 1.0);
        assert!(ours.starts_with("controller: silrig-controller (pid 7) never joined"), "{ours}");
        assert!(ours.contains("controller.stderr.log"), "{ours}");
        let exited = exited_before_joining(Role::Controller, "x", "exit status 3", 0.04, "; its stderr ends: no");
        assert_eq!(
            exited,
            "controller: x ended before it joined the run (exit status 3, 0.0 s after it started); its stderr ends: no"
        );
    }
}
