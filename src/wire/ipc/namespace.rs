//! One run, one namespace: a run id gives its processes an iceoryx2 root dir and file prefix no other run sees
//! ([`RunId`], [`rig_config`]), nodes are created in it ([`create_node`]), and everything the run left behind is
//! removed at its end, or by the next run after a crash ([`cleanup_run`]).

use super::IpcError;
use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;
use std::path::PathBuf;

/// Longest run id; keeps the prefix, and every shm name built from it, short.
pub const RUN_ID_MAX_LEN: usize = 24;

/// The name of one rig run: its processes share an iceoryx2 namespace that no other run sees.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunId(String);

impl RunId {
    /// Validate: 1..=24 characters of `[a-z0-9-]`. No `_`, so one run's prefix `sr_<run>_` can never be the start of
    /// another run's prefix, and cleanup of one run cannot touch another run's files.
    pub fn new(id: &str) -> Result<Self, IpcError> {
        let bad = |reason| Err(IpcError::InvalidRunId { given: id.to_string(), reason });
        if id.is_empty() {
            return bad("it is empty");
        }
        if id.len() > RUN_ID_MAX_LEN {
            return bad("it is too long");
        }
        if !id.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-') {
            return bad("it contains a character outside [a-z0-9-]");
        }
        Ok(Self(id.to_string()))
    }

    /// The id.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Prefix of every iceoryx2 file of the run, in `/dev/shm` and under the root dir: `sr_<run>_`.
    pub fn prefix(&self) -> String {
        format!("sr_{}_", self.0)
    }

    /// Root directory of the run's iceoryx2 files: `/dev/shm/silrig_<run>/`. In memory, beside the run's shared
    /// memory: iceoryx2 creates about a hundred files there a run (nodes, services, event sockets) and syncs each
    /// static one to its disk, which on a disk-backed `/tmp` made half of a sweep case's time (ext4 without a
    /// journal, as on this kind of VM, also scans past every file deleted in the last minutes to make one).
    pub fn root_dir(&self) -> PathBuf {
        PathBuf::from(format!("{SHM_DIR}/silrig_{}/", self.0))
    }
}

impl std::fmt::Display for RunId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::str::FromStr for RunId {
    type Err = IpcError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::new(s)
    }
}

/// The iceoryx2 config of a run: its own root dir and file prefix, defaults otherwise. Every process of the run must
/// use exactly this config (passed explicitly, so no `./config/iceoryx2.toml` in the working directory can change
/// it).
pub fn rig_config(run: &RunId) -> Config {
    quiet_transport_log();
    let mut cfg = Config::default();
    // A validated RunId gives an absolute path and a file name of [a-z0-9_-], both far below iceoryx2's length
    // limits, so these conversions cannot fail.
    let root = run.root_dir();
    let root = root.to_string_lossy();
    let root = Path::new(root.as_bytes()).expect("a validated run id gives a valid iceoryx2 path");
    cfg.global.set_root_path(&root);
    cfg.global.prefix = FileName::new(run.prefix().as_bytes()).expect("a validated run id gives a valid prefix");
    cfg
}

/// iceoryx2 prints its warnings on the process's stderr in its internal calls and types
/// (`Service::remove_node_from_service(UniqueNodeId(UniqueId { .. }))`), and a process's stderr ends up in the run's
/// messages (the tail quoted when it dies): only its errors are printed, unless `IOX2_LOG_LEVEL` asks for more (to
/// debug the transport). Set once per process, by the first use of a run's config, which every node and cleanup
/// goes through.
fn quiet_transport_log() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| set_log_level_from_env_or(LogLevel::Error));
}

/// Create a node of the run with the run's config. Every file the run has is left readable and writable by its
/// owner only.
pub fn create_node(run: &RunId, name: &str) -> Result<Node<ipc::Service>, IpcError> {
    let node_name =
        NodeName::new(name).map_err(|e| IpcError::Name { name: name.into(), detail: super::in_words(&e) })?;
    let node =
        NodeBuilder::new().name(&node_name).config(&rig_config(run)).create::<ipc::Service>().map_err(|e| {
            IpcError::Node { run: run.to_string(), node: name.into(), detail: node_failure_detail(run, e) }
        })?;
    restrict_global_mgmt(run);
    Ok(node)
}

/// iceoryx2's reason in words (its error prints as `NodeCreationFailure::...`), with the cause we can see: a run's
/// root path taken by something that is not a folder of ours, or a run of another user, whose files are owner-only.
fn node_failure_detail(run: &RunId, failure: iceoryx2::node::NodeCreationFailure) -> String {
    use iceoryx2::node::NodeCreationFailure as F;
    use std::os::unix::fs::MetadataExt;
    let root = run.root_dir();
    // Without its trailing slash, so that a file there is seen as one.
    let root = root.components().as_path().to_path_buf();
    let reason = match failure {
        F::InsufficientPermissions => "no permission to create its files",
        F::InternalError => "iceoryx2 failed inside",
        F::SystemCorrupted => "another process removed the run's files meanwhile (a cleanup of this run id?)",
        F::UnableToGenerateUniqueNodeId => "it could not take a node id from the run's shared counter",
    };
    // SAFETY: geteuid has no preconditions.
    let me = unsafe { libc::geteuid() };
    match std::fs::symlink_metadata(&root) {
        Ok(m) if !m.is_dir() => format!(
            "{} exists and is not a folder (it is where iceoryx2 keeps the run's state): remove it, or choose another \
             run id ({reason})",
            root.display()
        ),
        Ok(m) if m.uid() != me && me != 0 => format!(
            "{reason}: the run's files ({}) belong to uid {}, and a run is its owner's alone: join it as that user, \
             or start a run of your own with another run id",
            root.display(),
            m.uid()
        ),
        _ => format!("{reason} (under {} and /dev/shm)", root.display()),
    }
}

/// iceoryx2 creates the node counter it shares between all nodes of a root path (`<prefix>node.<version>.global_mgmt`
/// in `/dev/shm`) writable by everyone, and the folders of the run's root path (`nodes/`, `services/`, one per node)
/// readable by the group; the run's other files are owner-only, and so should these be. Every node narrows them
/// after creating itself and after opening its streams (what it created exists by then; narrowing twice is
/// harmless).
fn restrict_global_mgmt(run: &RunId) {
    use std::os::unix::fs::PermissionsExt;
    let prefix = run.prefix();
    for entry in std::fs::read_dir(SHM_DIR).into_iter().flatten().flatten() {
        let name = entry.file_name();
        let name = name.to_string_lossy();
        if name.starts_with(&prefix) && name.ends_with(".global_mgmt") {
            let _ = std::fs::set_permissions(entry.path(), std::fs::Permissions::from_mode(0o600));
        }
    }
    restrict_root_path(&run.root_dir());
}

/// Everything under a run's iceoryx2 root path made owner-only: folders 0700, files without group or other bits.
pub(crate) fn restrict_root_path(root: &std::path::Path) {
    use std::os::unix::fs::PermissionsExt;
    let mut stack = vec![root.to_path_buf()];
    while let Some(path) = stack.pop() {
        let Ok(meta) = std::fs::symlink_metadata(&path) else { continue };
        let mode = meta.permissions().mode() & 0o777;
        if mode & 0o077 != 0 {
            let narrowed = if meta.is_dir() { 0o700 } else { mode & 0o700 };
            let _ = std::fs::set_permissions(&path, std::fs::Permissions::from_mode(narrowed));
        }
        if meta.is_dir() {
            stack.extend(std::fs::read_dir(&path).into_iter().flatten().flatten().map(|e| e.path()));
        }
    }
}

/// Remove the resources of the run's dead nodes (a process that was killed), leaving the live ones alone; returns
/// the nodes removed. The launcher does this when it reaps a death, so that no process of the run pays for it
/// inside its loop.
pub fn cleanup_dead_nodes(run: &RunId) -> Result<Vec<NodeSummary>, IpcError> {
    let mut removed = Vec::new();
    if !run.root_dir().is_dir() {
        return Ok(removed);
    }
    Node::<ipc::Service>::list(&rig_config(run), |state| {
        if let NodeState::Dead(view) = state {
            let who = summary_of(view.details());
            if view.try_remove_stale_resources().is_ok() {
                removed.push(who);
            }
        }
        CallbackProgression::Continue
    })
    .map_err(|e| IpcError::Cleanup {
        run: run.to_string(),
        detail: format!("listing nodes: {}", super::in_words(&e)),
    })?;
    Ok(removed)
}

/// A node of the run as the launcher sees it: whose process it is, and whether that process still holds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NodeOfRun {
    /// The process that created it.
    pub pid: i64,
    /// Its process is alive (a dead one's node stays until it is cleaned up).
    pub alive: bool,
}

/// Every node of the run, alive or dead and not cleaned up yet: who has joined it (the launcher tells a role that
/// never joined from one that did by these pids). A node being created or removed while it looks is left out; no
/// root folder yet means nobody has joined.
pub fn nodes_of_run(run: &RunId) -> Result<Vec<NodeOfRun>, IpcError> {
    let mut nodes = Vec::new();
    if !run.root_dir().is_dir() {
        return Ok(nodes);
    }
    Node::<ipc::Service>::list(&rig_config(run), |state| {
        let (view_pid, alive) = match &state {
            NodeState::Alive(view) => (view.details().as_ref().map(|d| d.process_id().value()), true),
            NodeState::Dead(view) => (view.details().as_ref().map(|d| d.process_id().value()), false),
            NodeState::Inaccessible(_) | NodeState::Undefined(_) => (None, false),
        };
        if let Some(pid) = view_pid {
            nodes.push(NodeOfRun { pid: i64::from(pid), alive });
        }
        CallbackProgression::Continue
    })
    .map_err(|e| IpcError::Cleanup {
        run: run.to_string(),
        detail: format!("listing nodes: {}", super::in_words(&e)),
    })?;
    Ok(nodes)
}

/// A node found during cleanup.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct NodeSummary {
    /// Node name ("?" if its details are gone).
    pub name: String,
    /// Process id (0 if unknown).
    pub pid: i64,
}

/// What [`cleanup_run`] did.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize)]
pub struct CleanupReport {
    /// Run id.
    pub run: String,
    /// Nodes still alive: when not empty, nothing was removed.
    pub alive: Vec<NodeSummary>,
    /// Dead nodes whose resources were removed.
    pub dead_cleaned: Vec<NodeSummary>,
    /// Dead nodes whose cleanup failed (or that another process was cleaning).
    pub dead_failed: Vec<NodeSummary>,
    /// Nodes that could not be inspected (permissions, half-written state).
    pub unknown: usize,
    /// The run's root dir was removed.
    pub removed_root_dir: bool,
    /// Files removed from `/dev/shm`.
    pub removed_shm_files: Vec<String>,
}

impl CleanupReport {
    /// Nothing of the run is left on disk.
    pub fn is_clean(&self) -> bool {
        self.alive.is_empty()
    }
}

fn summary_of(details: &Option<iceoryx2::node::NodeDetails>) -> NodeSummary {
    match details {
        Some(d) => NodeSummary { name: d.name().to_string(), pid: i64::from(d.process_id().value()) },
        None => NodeSummary { name: "?".into(), pid: 0 },
    }
}

/// Directory where iceoryx2 puts shared memory on Linux.
pub const SHM_DIR: &str = "/dev/shm";

/// End-of-run cleanup: remove the resources of the run's dead nodes through iceoryx2, then, only if no node of the
/// run is alive, delete the run's root dir and its `/dev/shm/<prefix>*` files (both, never only one: iceoryx2 #601).
/// With live nodes, reports them and removes nothing. Reap child processes first: a zombie still holds its node's
/// liveness lock.
pub fn cleanup_run(run: &RunId) -> Result<CleanupReport, IpcError> {
    let cfg = rig_config(run);
    let mut report = CleanupReport { run: run.to_string(), ..Default::default() };
    let root = run.root_dir();
    if root.exists() {
        Node::<ipc::Service>::list(&cfg, |state| {
            match state {
                NodeState::Alive(view) => report.alive.push(summary_of(view.details())),
                NodeState::Dead(view) => {
                    let who = summary_of(view.details());
                    match view.try_remove_stale_resources() {
                        Ok(()) => report.dead_cleaned.push(who),
                        Err(_) => report.dead_failed.push(who),
                    }
                }
                NodeState::Inaccessible(_) | NodeState::Undefined(_) => report.unknown += 1,
            }
            CallbackProgression::Continue
        })
        .map_err(|e| IpcError::Cleanup {
            run: run.to_string(),
            detail: format!("listing nodes: {}", super::in_words(&e)),
        })?;
    }
    if !report.alive.is_empty() {
        return Ok(report);
    }
    if root.exists() {
        std::fs::remove_dir_all(&root).map_err(|e| IpcError::Cleanup {
            run: run.to_string(),
            detail: format!("removing {}: {e}", root.display()),
        })?;
        report.removed_root_dir = true;
    }
    let prefix = run.prefix();
    let entries = std::fs::read_dir(SHM_DIR)
        .map_err(|e| IpcError::Cleanup { run: run.to_string(), detail: format!("reading {SHM_DIR}: {e}") })?;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with(&prefix) {
            match std::fs::remove_file(entry.path()) {
                Ok(()) => report.removed_shm_files.push(name),
                // Another cleaner got there first.
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => {
                    return Err(IpcError::Cleanup {
                        run: run.to_string(),
                        detail: format!("removing {SHM_DIR}/{name}: {e}"),
                    });
                }
            }
        }
    }
    Ok(report)
}

/// Leftovers younger than this are left alone when their nodes cannot be inspected: a run may be starting.
const UNINSPECTABLE_GRACE: std::time::Duration = std::time::Duration::from_secs(60);
/// ... and for this long even when every node is dead: the run's own launcher (or test) cleans up a moment after
/// its processes end, and may be looking at its leftovers.
pub const DEAD_RUN_GRACE: std::time::Duration = std::time::Duration::from_secs(5);

/// Run ids that have files on this machine: `/dev/shm/silrig_<run>/` folders and `/dev/shm/sr_<run>_*` files, with
/// the time the newest of them was modified.
fn runs_on_this_machine() -> Vec<(RunId, std::time::SystemTime)> {
    let mut runs: std::collections::BTreeMap<String, std::time::SystemTime> = Default::default();
    let mut note = |id: Option<&str>, entry: &std::fs::DirEntry| {
        let (Some(id), Ok(modified)) = (id, entry.metadata().and_then(|m| m.modified())) else { return };
        let newest = runs.entry(id.to_string()).or_insert(modified);
        *newest = (*newest).max(modified);
    };
    for entry in std::fs::read_dir(SHM_DIR).into_iter().flatten().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let id = match name.strip_prefix("silrig_") {
            Some(root) => Some(root),
            None => name.strip_prefix("sr_").and_then(|rest| rest.split('_').next()),
        };
        note(id, &entry);
    }
    runs.into_iter().filter_map(|(id, t)| RunId::new(&id).ok().map(|r| (r, t))).collect()
}

/// Remove what dead runs left on this machine (a launcher killed with `kill -9`, a crashed test): every run other
/// than `except` with no live node whose files are older than [`DEAD_RUN_GRACE`]. A run whose nodes cannot all
/// be inspected is left alone for a minute after its files last changed, since it may be starting. Returns the
/// runs cleaned.
pub fn cleanup_dead_runs(except: &RunId) -> Vec<CleanupReport> {
    let mut cleaned = Vec::new();
    for (run, newest) in runs_on_this_machine() {
        if run == *except {
            continue;
        }
        let age = newest.elapsed().unwrap_or_default();
        if age < DEAD_RUN_GRACE {
            continue;
        }
        let young = age < UNINSPECTABLE_GRACE;
        let cfg = rig_config(&run);
        let (mut alive, mut unknown) = (0, 0);
        if run.root_dir().exists() {
            let listed = Node::<ipc::Service>::list(&cfg, |state| {
                match state {
                    NodeState::Alive(_) => alive += 1,
                    NodeState::Inaccessible(_) | NodeState::Undefined(_) => unknown += 1,
                    NodeState::Dead(_) => {}
                }
                CallbackProgression::Continue
            });
            if listed.is_err() {
                unknown += 1;
            }
        } else {
            // Shared memory without the run's folder: what a cleanup interrupted half way leaves.
            unknown += 1;
        }
        if alive > 0 || (unknown > 0 && young) {
            continue;
        }
        if let Ok(report) = cleanup_run(&run)
            && report.is_clean()
            && (report.removed_root_dir || !report.removed_shm_files.is_empty())
        {
            cleaned.push(report);
        }
    }
    cleaned
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_id_is_validated() {
        assert!(RunId::new("r42").is_ok());
        assert!(RunId::new("a-b-0").is_ok());
        assert!(RunId::new(&"x".repeat(24)).is_ok());
        for bad in ["", "Run1", "a_b", "a/b", "a b", "ü"] {
            let e = RunId::new(bad).unwrap_err().to_string();
            assert!(e.contains("invalid run id") && e.contains("a-z, 0-9 and '-'"), "{e}");
        }
        assert!(RunId::new(&"x".repeat(25)).unwrap_err().to_string().contains("too long"));
        let r = RunId::new("r42").unwrap();
        assert_eq!(r.prefix(), "sr_r42_");
        assert_eq!(r.root_dir(), PathBuf::from("/dev/shm/silrig_r42/"));
        let cfg = rig_config(&r);
        assert_eq!(cfg.global.prefix.as_str(), "sr_r42_");
        assert_eq!(cfg.global.root_path().to_string(), "/dev/shm/silrig_r42/");
    }
}
