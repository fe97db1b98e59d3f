//! The plant's newest checkpoint in shared memory (`/dev/shm/sr_<run>_plant.checkpoint`), stored by the real-time
//! loop itself with no system call, so that a restarted plant resumes from the newest checkpoint its predecessor
//! took, however late the checkpoint file's writer thread runs.
//!
//! Why: `plant.checkpoint.json` is written by a thread at normal priority (file I/O stays off the real-time loop).
//! On a machine whose CPUs real-time work keeps busy (other rigs, a controller at SCHED_FIFO) that thread runs only
//! in the kernel's 5 % real-time throttling window, and the file fell up to 96 ticks behind the flight; a plant
//! killed then resumed from a checkpoint 40 to 98 ticks old. Stores to a tmpfs mapping are memory writes: the slot
//! is never older than the last checkpoint the loop took. The file stays, written as before, for a plant resumed
//! after the run's shared memory was removed (`--resume` by hand after the launcher's end).
//!
//! Two slots, written alternately, each with a sequence word that is odd while the slot is being written and twice
//! its generation once whole: a plant killed mid-store leaves the other slot whole, and the reader takes the whole
//! slot of the highest generation. Only read by a restarted plant, when its predecessor is dead.

use silrig_wire::ipc::RunId;
use std::os::fd::AsRawFd;
use std::os::unix::fs::OpenOptionsExt;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

/// Bytes of text one slot holds; a larger checkpoint (a big FMU's state) goes to the file alone.
pub const SLOT_TEXT_BYTES: usize = 256 * 1024;
/// Per slot: the sequence word and the text's length, then the text.
const HEADER_BYTES: usize = 16;
const SLOT_BYTES: usize = HEADER_BYTES + SLOT_TEXT_BYTES;
const BYTES: usize = 2 * SLOT_BYTES;

/// Where a run's slot lives.
pub fn slot_path(run: &RunId) -> PathBuf {
    PathBuf::from(silrig_wire::ipc::SHM_DIR).join(format!("{}plant.checkpoint", run.prefix()))
}

/// The mapped slots of one run.
#[derive(Debug)]
pub struct CheckpointSlot {
    base: *mut u8,
    /// The generation of the next store.
    next_generation: u64,
}

// SAFETY: the mapping lives as long as the value; only the owner writes through it.
unsafe impl Send for CheckpointSlot {}

impl CheckpointSlot {
    /// Map the run's slots (created if missing), populated now so the loop's stores never fault. `fresh`: a plant
    /// that is not resuming forgets whatever a previous life of the run stored.
    pub fn open(run: &RunId, fresh: bool) -> std::io::Result<Self> {
        let file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .mode(0o600)
            .open(slot_path(run))?;
        file.set_len(BYTES as u64)?;
        let flags = libc::MAP_SHARED | libc::MAP_POPULATE;
        let prot = libc::PROT_READ | libc::PROT_WRITE;
        // SAFETY: a shared mapping of BYTES bytes of a file that long; checked below, unmapped in Drop.
        let at = unsafe { libc::mmap(std::ptr::null_mut(), BYTES, prot, flags, file.as_raw_fd(), 0) };
        if at == libc::MAP_FAILED {
            return Err(std::io::Error::last_os_error());
        }
        let mut slot = Self { base: at.cast(), next_generation: 1 };
        if fresh {
            (0..2).for_each(|i| slot.sequence(i).store(0, Ordering::Release));
        }
        slot.next_generation = slot.whole().map_or(0, |(generation, _)| generation) + 1;
        Ok(slot)
    }

    fn sequence(&self, i: usize) -> &AtomicU64 {
        // SAFETY: slot i's first word, inside the mapping and 8-byte aligned (the mapping is page-aligned and
        // SLOT_BYTES is a multiple of 8).
        unsafe { &*self.base.add(i * SLOT_BYTES).cast::<AtomicU64>() }
    }

    fn length(&self, i: usize) -> &AtomicU64 {
        // SAFETY: as in `sequence`, the word after it.
        unsafe { &*self.base.add(i * SLOT_BYTES + 8).cast::<AtomicU64>() }
    }

    /// Store `text` as the newest checkpoint: memory writes only. False when it is larger than a slot: then both
    /// slots are emptied, so a restarted plant takes the file rather than an older checkpoint from here.
    pub fn store(&mut self, text: &str) -> bool {
        if text.len() > SLOT_TEXT_BYTES {
            (0..2).for_each(|i| self.sequence(i).store(0, Ordering::Release));
            return false;
        }
        let generation = self.next_generation;
        let i = (generation % 2) as usize;
        self.sequence(i).store(2 * generation - 1, Ordering::Release);
        self.length(i).store(text.len() as u64, Ordering::Relaxed);
        // SAFETY: the slot's text area, SLOT_TEXT_BYTES long, holds text.len() bytes (checked above); nothing else
        // writes it, and a reader takes it only once the sequence word says whole.
        unsafe {
            std::ptr::copy_nonoverlapping(text.as_ptr(), self.base.add(i * SLOT_BYTES + HEADER_BYTES), text.len());
        }
        self.sequence(i).store(2 * generation, Ordering::Release);
        self.next_generation += 1;
        true
    }

    /// The whole slot of the highest generation: (generation, text); None when neither is whole.
    fn whole(&self) -> Option<(u64, String)> {
        (0..2)
            .filter_map(|i| {
                let sequence = self.sequence(i).load(Ordering::Acquire);
                let len = self.length(i).load(Ordering::Relaxed) as usize;
                if sequence == 0 || sequence % 2 == 1 || len > SLOT_TEXT_BYTES {
                    return None;
                }
                // SAFETY: len bytes of the slot's text area (checked against its size).
                let bytes = unsafe { std::slice::from_raw_parts(self.base.add(i * SLOT_BYTES + HEADER_BYTES), len) };
                let text = std::str::from_utf8(bytes).ok()?.to_owned();
                (self.sequence(i).load(Ordering::Acquire) == sequence).then_some((sequence / 2, text))
            })
            .max_by_key(|(generation, _)| *generation)
    }

    /// The newest whole checkpoint stored (by this plant's predecessor, for a restarted plant).
    pub fn newest(&self) -> Option<String> {
        self.whole().map(|(_, text)| text)
    }
}

impl Drop for CheckpointSlot {
    fn drop(&mut self) {
        // SAFETY: exactly the mapping `open` made, unmapped once.
        unsafe { libc::munmap(self.base.cast(), BYTES) };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(test: &str) -> RunId {
        RunId::new(&format!("slot-{test}-{}", std::process::id())).unwrap()
    }

    #[test]
    fn a_restarted_plant_reads_the_newest_store_and_a_fresh_one_nothing() {
        let id = run("newest");
        let mut first = CheckpointSlot::open(&id, true).unwrap();
        assert_eq!(first.newest(), None);
        for tick in [10, 20, 30] {
            assert!(first.store(&format!("{{\"tick\":{tick}}}")));
        }
        drop(first);
        let mut again = CheckpointSlot::open(&id, false).unwrap();
        assert_eq!(again.newest().as_deref(), Some("{\"tick\":30}"));
        // Its own stores continue the generations, so they win over the predecessor's.
        again.store("{\"tick\":40}");
        assert_eq!(CheckpointSlot::open(&id, false).unwrap().newest().as_deref(), Some("{\"tick\":40}"));
        assert_eq!(CheckpointSlot::open(&id, true).unwrap().newest(), None, "a fresh plant forgets");
        std::fs::remove_file(slot_path(&id)).unwrap();
    }

    #[test]
    fn a_store_cut_short_leaves_the_previous_checkpoint_and_one_too_large_leaves_none() {
        let id = run("torn");
        let mut slot = CheckpointSlot::open(&id, true).unwrap();
        slot.store("{\"tick\":10}");
        slot.store("{\"tick\":20}");
        // Killed in the middle of the next store: its slot's sequence word is odd.
        let i = (slot.next_generation % 2) as usize;
        slot.sequence(i).store(2 * slot.next_generation - 1, Ordering::Release);
        assert_eq!(slot.newest().as_deref(), Some("{\"tick\":20}"));
        assert!(!slot.store(&"x".repeat(SLOT_TEXT_BYTES + 1)));
        assert_eq!(slot.newest(), None, "the file is then the newest checkpoint");
        std::fs::remove_file(slot_path(&id)).unwrap();
    }
}
