//! Where a sweep's cases fly through the lockstep rig: a scratch folder with one run folder per case in flight
//! (removed once its case is judged, so a sweep of any length leaves no run folders), and each worker thread's
//! warm rig ([`silrig_launch::warm::WarmRig`]): its plant, logger and controller programs started on the thread's
//! first case and kept, each case's processes forked from them. A case whose rig failed (a crash, a silence)
//! starts that thread's rig again cold; the campaign goes on.
//!
//! Each rig's first case is flown twice, and the two traces must be the same bytes: a controller that keeps state
//! from one flight to the next (in a file, say, which a fork does not undo) flies the second differently, is named
//! on stderr, and the sweep flies every later case cold (`--cold` asks for that from the start). A program that
//! cannot fly warm (it speaks the contract without silrig's libraries) is flown cold too, said once.

use super::case::CaseResult;
use super::rig_case::{Interrupted, fly_in};
use silrig_launch::launcher;
use silrig_launch::warm::WarmRig;
use silrig_rig::{ProcessArgs, ProcessOptions, RigMode};
use silrig_wire::ipc::RunId;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::ThreadId;
use std::time::Duration;

/// `SILRIG_SWEEP_KEEP=dir`: each case's `trace.csv` is kept there as `case-<i>.trace.csv` (for tests that compare
/// warm cases with cold ones).
pub const KEEP_ENV: &str = "SILRIG_SWEEP_KEEP";

/// One worker thread's warm rig and how many cases it has flown.
struct Slot {
    rig: Arc<WarmRig>,
    flights: u64,
}

/// A sweep's scratch folder and its warm rigs (see the module doc).
pub struct Scratch {
    dir: PathBuf,
    /// The sweep's run id; case i flies as `<it>-<i in hex>`, unique on this machine while the sweep runs.
    run_id: RunId,
    /// Each worker thread's rig: the programs' death is tied to the thread that started them.
    rigs: Mutex<HashMap<ThreadId, Slot>>,
    /// Every case flies cold from now on.
    cold: AtomicBool,
    keep: Option<PathBuf>,
}

impl Scratch {
    /// A fresh scratch folder in the system's temporary folder, named by a fresh run id; `cold`: every case in
    /// fresh processes.
    pub fn new(cold: bool) -> anyhow::Result<Self> {
        let run_id = launcher::fresh_run_id();
        let dir = std::env::temp_dir().join(format!("silrig-sweep-{run_id}"));
        std::fs::create_dir_all(&dir)?;
        let keep = std::env::var_os(KEEP_ENV).map(PathBuf::from);
        if let Some(keep) = &keep {
            std::fs::create_dir_all(keep)?;
        }
        Ok(Self { dir, run_id, rigs: Mutex::new(HashMap::new()), cold: AtomicBool::new(cold), keep })
    }

    /// Fly case `index` in a run folder of its own (through this thread's warm rig unless cold), judge it and
    /// remove the folder.
    pub fn fly(&self, campaign: &super::Campaign, seed: u64, index: u64) -> Result<CaseResult, Interrupted> {
        let warm = self.rig(campaign);
        let run_dir = self.dir.join(format!("case-{index}"));
        let flown = fly_in(campaign, (seed, index), &run_dir, Some(&self.case_id(index, "")), false, warm.clone());
        let trace = std::fs::read(run_dir.join("trace.csv")).unwrap_or_default();
        let _ = std::fs::remove_dir_all(&run_dir);
        let (result, _, failed) = flown?;
        if let Some(keep) = &self.keep {
            let _ = std::fs::write(keep.join(format!("case-{index}.trace.csv")), &trace);
        }
        if warm.is_some() {
            let first = self.after_flight(failed);
            if first && !failed {
                self.check_afresh(campaign, (seed, index), &trace, warm)?;
            }
        }
        Ok(result)
    }

    /// Case `index`'s run id, with `suffix`.
    fn case_id(&self, index: u64, suffix: &str) -> RunId {
        RunId::new(&format!("{}-{index:x}{suffix}", self.run_id)).expect("a run id and a hex number make one")
    }

    /// This thread's warm rig, started if it has none; `None` when the sweep flies cold (a rig that cannot start
    /// makes it so, said once).
    fn rig(&self, campaign: &super::Campaign) -> Option<Arc<WarmRig>> {
        if self.cold.load(Ordering::Relaxed) {
            return None;
        }
        let thread = std::thread::current().id();
        if let Some(slot) = self.rigs.lock().expect("no thread panics holding it").get(&thread) {
            return Some(Arc::clone(&slot.rig));
        }
        let n = self.rigs.lock().expect("not poisoned").len();
        let dir = self.dir.join(format!("rig-{n}"));
        let args = ProcessArgs {
            config: None,
            run_id: self.case_id(n as u64, "-w"),
            mode: RigMode::Lockstep,
            duration_s: None,
            out: dir.clone(),
            resume: false,
            options: ProcessOptions::default(),
        };
        let commands = (campaign.commands.controller_cmd.as_deref(), campaign.commands.plant_cmd.as_deref());
        let ready_within = Duration::from_secs_f64(args.options.startup_timeout_s);
        match WarmRig::start(commands, &args, &dir, ready_within) {
            Ok(rig) => {
                let rig = Arc::new(rig);
                let slot = Slot { rig: Arc::clone(&rig), flights: 0 };
                self.rigs.lock().expect("not poisoned").insert(thread, slot);
                Some(rig)
            }
            Err(e) => {
                self.go_cold(&format!("{e:#}"));
                None
            }
        }
    }

    /// Count this thread's flight; a failed one drops its rig (the next case starts it again cold). True after the
    /// rig's first flight.
    fn after_flight(&self, failed: bool) -> bool {
        let thread = std::thread::current().id();
        let mut rigs = self.rigs.lock().expect("not poisoned");
        if failed {
            rigs.remove(&thread);
            return false;
        }
        rigs.get_mut(&thread).is_some_and(|slot| {
            slot.flights += 1;
            slot.flights == 1
        })
    }

    /// Fly the rig's first case again in it; another trace means a program kept state from the first flight.
    fn check_afresh(
        &self,
        campaign: &super::Campaign,
        case: (u64, u64),
        first: &[u8],
        warm: Option<Arc<WarmRig>>,
    ) -> Result<(), Interrupted> {
        let index = case.1;
        let run_dir = self.dir.join(format!("case-{index}-again"));
        let flown = fly_in(campaign, case, &run_dir, Some(&self.case_id(index, "-a")), false, warm);
        let again = std::fs::read(run_dir.join("trace.csv")).unwrap_or_default();
        let _ = std::fs::remove_dir_all(&run_dir);
        // A rig that failed the second time (a crash, a silence, a loaded machine's timeout) says nothing of state
        // kept: it is started again, as after any failed case.
        if flown?.2 {
            self.after_flight(true);
            return Ok(());
        }
        if let Some(row) = first_difference(first, &again) {
            self.go_cold(&format!(
                "case {index} flown a second time in the same warm processes gave another trace.csv (from its line \
                 {row}): a program of the rig keeps state from one flight to the next, which a warm rig's flights \
                 must not (each flight starts afresh: see the contract's warm rigs); fix it to fly warm"
            ));
        }
        Ok(())
    }

    /// From now on every case flies cold; say why, once.
    fn go_cold(&self, why: &str) {
        if !self.cold.swap(true, Ordering::Relaxed) {
            eprintln!("silrig sweep: {why}; flying every case cold (fresh processes) from here");
        }
        self.rigs.lock().expect("not poisoned").clear();
    }

    /// The scratch folder (for tests).
    pub fn dir(&self) -> &Path {
        &self.dir
    }
}

/// The first line (from 1) where two files differ, or `None` when they are the same bytes.
fn first_difference(a: &[u8], b: &[u8]) -> Option<usize> {
    if a == b {
        return None;
    }
    let same = a.iter().zip(b).take_while(|(x, y)| x == y).count();
    Some(a[..same].iter().filter(|&&c| c == b'\n').count() + 1)
}

impl Drop for Scratch {
    fn drop(&mut self) {
        self.rigs.lock().map(|mut r| r.clear()).ok();
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

#[cfg(test)]
mod tests {
    use super::first_difference;

    #[test]
    fn the_first_difference_is_named_by_its_line() {
        assert_eq!(first_difference(b"a\nb\nc\n", b"a\nb\nc\n"), None);
        assert_eq!(first_difference(b"a\nb\nc\n", b"a\nx\nc\n"), Some(2));
        assert_eq!(first_difference(b"a\nb\n", b"a\nb\nc\n"), Some(3));
        assert_eq!(first_difference(b"", b"a"), Some(1));
    }
}
