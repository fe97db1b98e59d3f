//! What makes a run its own: its run id ([`fresh_run_id`]) and the lock files that claim its folder and its run id
//! for one launcher ([`Claim`]), taken over when their launcher died ([`remove_stale_claims`]), and the check that
//! refuses an output folder already holding a run's files ([`refuse_used_folder`]).

use anyhow::Context;
use silrig_wire::ipc::RunId;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// A fresh run id: short, lowercase, unique per launcher process and start time.
pub fn fresh_run_id() -> RunId {
    let t = silrig_wire::clock::monotonic_ns();
    let id = format!("r{:x}-{:x}", std::process::id(), (t / 1_000) & 0xff_ffff);
    RunId::new(&id).expect("generated run ids are valid")
}

/// Files only a run writes into its folder, a failed run's included (it writes no `trace.csv`, but its events,
/// report and recording): a folder holding any of them belongs to an earlier run.
const RUN_FILES: [&str; 4] = ["trace.csv", "report.json", "events.jsonl", "recording.mcap"];

/// Refuse `out` as a run's folder: a file where the folder should be, or a folder that holds an earlier run's files
/// (reusing it would mix two runs' events and recordings, and nothing already recorded may be lost).
pub fn refuse_used_folder(out: &Path) -> anyhow::Result<()> {
    if out.exists() && !out.is_dir() {
        anyhow::bail!("--out {}: it is a file, not a folder: choose a folder for the run's files", out.display());
    }
    if let Some(found) = RUN_FILES.iter().find(|name| out.join(name).exists()) {
        anyhow::bail!(
            "{} already holds a run ({found}); choose another --out or move it away: nothing is overwritten",
            out.display()
        );
    }
    Ok(())
}

/// A lock file created exclusively (check and create in one step), holding the launcher's pid, removed when the
/// run ends: two launchers never share a folder or a run id. A claim whose launcher died is taken over.
pub(crate) struct Claim(PathBuf);

impl Claim {
    pub(crate) fn take(path: PathBuf, what: &str) -> anyhow::Result<Self> {
        // The claim appears with its pid in it (written beside it, then linked into place: a link never replaces),
        // so a run that finds it taken can always say by whom.
        let staged = PathBuf::from(format!("{}.{}", path.display(), std::process::id()));
        std::fs::write(&staged, std::process::id().to_string())
            .with_context(|| format!("writing {}", staged.display()))?;
        let claimed = (|| {
            for _ in 0..2 {
                match std::fs::hard_link(&staged, &path) {
                    Ok(()) => return Ok(Self(path.clone())),
                    Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {
                        if let Some(holder) = live_holder(&path) {
                            let who = holder.map_or(
                                "another user's, or one just starting: its pid cannot be read".to_string(),
                                |pid| format!("pid {pid}"),
                            );
                            anyhow::bail!(
                                "{what} is taken by another silrig run ({who}): wait for it, or choose another"
                            );
                        }
                        // Its launcher died without removing it.
                        let _ = std::fs::remove_file(&path);
                    }
                    Err(e) => return Err(e).with_context(|| format!("creating {}", path.display())),
                }
            }
            anyhow::bail!("{what}: cannot claim {} (another run keeps taking it)", path.display())
        })();
        let _ = std::fs::remove_file(&staged);
        claimed
    }
}

/// The holder of a claim file if it is alive: `Some(Some(pid))`; `Some(None)` for one whose pid cannot be read:
/// another user's (owner-only), or without a pid (written by an older silrig) and too fresh to call abandoned.
fn live_holder(path: &Path) -> Option<Option<i32>> {
    let text = match std::fs::read_to_string(path) {
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => return Some(None),
        read => read.ok(),
    };
    let holder: Option<i32> = text.and_then(|t| t.trim().parse().ok());
    match holder {
        // SAFETY: kill with signal 0 only asks whether the process exists.
        Some(pid) => (pid > 0 && unsafe { libc::kill(pid, 0) } == 0).then_some(Some(pid)),
        None => {
            let age = std::fs::metadata(path).and_then(|m| m.modified()).ok().and_then(|t| t.elapsed().ok());
            age.is_none_or(|a| a < Duration::from_secs(5)).then_some(None)
        }
    }
}

/// Remove run-id claims (`/tmp/silrig_<run>.lock`) whose launcher died (a `kill -9`); returns how many.
pub(crate) fn remove_stale_claims() -> usize {
    let mut removed = 0;
    for entry in std::fs::read_dir("/tmp").into_iter().flatten().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("silrig_") && name.ends_with(".lock") && live_holder(&entry.path()).is_none() {
            removed += usize::from(std::fs::remove_file(entry.path()).is_ok());
        }
    }
    removed
}

impl Drop for Claim {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}
