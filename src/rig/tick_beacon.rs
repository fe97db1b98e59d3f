//! The plant's newest published tick, for the launcher's process faults: a 16-byte file in the run's status folder
//! (`/dev/shm/silrig_<run>/status/plant.tick`), mapped by the plant, which stores the tick after each publish (one atomic
//! store, no system call), and mapped read-only by `silrig run`, which then kills, stops and terminates processes at
//! their planned simulated time, the tick, rather than at a wall-clock time from tick 0 that a stalled or restarted
//! plant has left behind. The run's cleanup removes it with the folder.

use super::status::status_dir;
use silrig_wire::ipc::RunId;
use std::fs::OpenOptions;
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

/// The mapped file: word 0 holds the newest published tick plus one (0: none yet), word 1 is reserved.
const BYTES: usize = 16;

/// The plant's end (writes) or the launcher's (reads) of a run's tick beacon.
#[derive(Debug)]
pub struct TickBeacon {
    word: *mut AtomicU64,
}

// SAFETY: the mapping lives as long as the value and is only touched through an atomic.
unsafe impl Send for TickBeacon {}

/// Where a run's beacon lives.
pub fn beacon_path(run: &RunId) -> PathBuf {
    status_dir(run).join("plant.tick")
}

impl TickBeacon {
    /// The plant's end: the file created (or reopened by a restarted plant) and mapped for writing, saying "no
    /// tick yet" until the first publish: a restarted plant has flown nothing yet, and a file a crashed run of the
    /// same id left must not fire the new run's faults at once.
    pub fn create(run: &RunId) -> std::io::Result<Self> {
        std::fs::create_dir_all(status_dir(run))?;
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .mode(0o600)
            .open(beacon_path(run))?;
        file.set_len(BYTES as u64)?;
        let beacon = Self::map(&file, libc::PROT_READ | libc::PROT_WRITE)?;
        // SAFETY: as in `publish`.
        unsafe { &*beacon.word }.store(0, Ordering::Release);
        Ok(beacon)
    }

    /// The launcher's end, once the plant has created it.
    pub fn open(run: &RunId) -> std::io::Result<Self> {
        let file = OpenOptions::new().read(true).open(beacon_path(run))?;
        if file.metadata()?.len() < BYTES as u64 {
            return Err(std::io::Error::other("the tick beacon is not written yet"));
        }
        Self::map(&file, libc::PROT_READ)
    }

    fn map(file: &std::fs::File, protection: libc::c_int) -> std::io::Result<Self> {
        // SAFETY: a shared mapping of BYTES bytes of a file at least that long; checked for failure below, unmapped
        // in Drop. The descriptor may close afterwards: the mapping keeps the file.
        let at = unsafe { libc::mmap(std::ptr::null_mut(), BYTES, protection, libc::MAP_SHARED, file.as_raw_fd(), 0) };
        if at == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error());
        }
        Ok(Self { word: at.cast() })
    }

    /// The plant has published `tick`.
    pub fn publish(&self, tick: u64) {
        // SAFETY: `word` points into our live mapping, page-aligned, so aligned for an AtomicU64.
        unsafe { &*self.word }.store(tick + 1, Ordering::Release);
    }

    /// The newest tick the plant has published, if any.
    pub fn newest(&self) -> Option<u64> {
        // SAFETY: as in `publish`; the mapping is readable on both ends.
        unsafe { &*self.word }.load(Ordering::Acquire).checked_sub(1)
    }
}

impl Drop for TickBeacon {
    fn drop(&mut self) {
        // SAFETY: exactly the mapping `map` made, unmapped once.
        unsafe { libc::munmap(self.word.cast(), BYTES) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_launcher_reads_what_the_plant_publishes_and_a_restarted_plant_starts_afresh() {
        let run = RunId::new(&format!("beacon-{}", std::process::id())).unwrap();
        assert!(TickBeacon::open(&run).is_err(), "nothing before the plant creates it");
        let plant = TickBeacon::create(&run).unwrap();
        let launcher = TickBeacon::open(&run).unwrap();
        assert_eq!(launcher.newest(), None);
        plant.publish(0);
        assert_eq!(launcher.newest(), Some(0));
        plant.publish(105);
        assert_eq!(launcher.newest(), Some(105));
        drop(plant);
        // A restarted plant has flown nothing until its first publish, then goes back to its checkpoint's tick.
        let again = TickBeacon::create(&run).unwrap();
        assert_eq!(launcher.newest(), None, "nothing flies while the plant restarts");
        again.publish(100);
        assert_eq!(launcher.newest(), Some(100));
        let _ = std::fs::remove_dir_all(run.root_dir());
    }
}
