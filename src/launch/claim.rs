//! What makes a run its own: its run id ([`fresh_run_id`]) and the lock files that claim its folder and its run id
//! for one launcher ([`Claim`]), taken over when their launcher died ([`remove_stale_claims`]) and refused, naming
//! the file and its owner, when another user's, and the check that
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
                        refuse_foreign(&path, what)?;
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

/// Refuse a claim file of another user, which this user can neither read (owner-only) nor remove (`/tmp` is sticky),
/// naming the file and its owner; root may read and remove any, so it goes on to look at the holder.
fn refuse_foreign(path: &Path, what: &str) -> anyhow::Result<()> {
    use std::os::unix::fs::MetadataExt;
    // SAFETY: geteuid has no preconditions.
    let me = unsafe { libc::geteuid() };
    let Ok(owner) = std::fs::symlink_metadata(path).map(|m| m.uid()) else { return Ok(()) };
    if me == 0 || owner == me {
        return Ok(());
    }
    anyhow::bail!(
        "{what} is claimed by {} of user {} (uid {owner}), which only that user or root can remove: choose another \
         run id, or ask them to remove it if no run of theirs uses it",
        path.display(),
        user_name(owner).unwrap_or_else(|| "?".into())
    )
}

/// The name of user `uid` from the system's user database.
fn user_name(uid: u32) -> Option<String> {
    let mut buf = vec![0 as libc::c_char; 4096];
    // SAFETY: getpwuid_r writes into `pwd` and `buf`, both ours and of the sizes given; `result` points into `pwd`.
    unsafe {
        let mut pwd: libc::passwd = std::mem::zeroed();
        let mut result: *mut libc::passwd = std::ptr::null_mut();
        let rc = libc::getpwuid_r(uid, &mut pwd, buf.as_mut_ptr(), buf.len(), &mut result);
        if rc != 0 || result.is_null() {
            return None;
        }
        Some(std::ffi::CStr::from_ptr(pwd.pw_name).to_string_lossy().into_owned())
    }
}

/// Whether process `pid` exists: kill(2) with signal 0 fails with EPERM for another user's live process.
fn alive(pid: i32) -> bool {
    // SAFETY: kill with signal 0 only asks whether the process exists.
    pid > 0
        && (unsafe { libc::kill(pid, 0) } == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM))
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
        Some(pid) => alive(pid).then_some(Some(pid)),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_claim_of_a_dead_launcher_is_taken_over_and_a_live_one_is_refused_with_its_pid() {
        let dir = std::env::temp_dir().join(format!("silrig-claim-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("silrig_x.lock");
        let mut gone = std::process::Command::new("true").spawn().unwrap();
        gone.wait().unwrap();
        std::fs::write(&path, gone.id().to_string()).unwrap();
        let claim = Claim::take(path.clone(), "run id x").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), std::process::id().to_string());
        let refused = Claim::take(path.clone(), "run id x").err().unwrap().to_string();
        assert_eq!(
            refused,
            format!(
                "run id x is taken by another silrig run (pid {}): wait for it, or choose another",
                std::process::id()
            )
        );
        drop(claim);
        assert!(!path.exists());
        assert!(alive(1), "init is alive, though this user may not signal it");
        assert_eq!(user_name(0).as_deref(), Some("root"));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
