//! Waiting: the WaitSet loop with the rig's signal rules ([`run_waitset`]: EINTR resumes, SIGTERM/SIGINT end it)
//! and a timerfd tick source on an absolute grid that a WaitSet can wait on next to listeners ([`TickTimer`]).

use super::IpcError;
use crate::clock;
use iceoryx2::prelude::*;
use iceoryx2::waitset::WaitSetRunResult;

/// A WaitSet for a rig process (iceoryx2's default signal handling; see the module doc).
pub fn rig_waitset() -> Result<WaitSet<ipc::Service>, IpcError> {
    WaitSetBuilder::new().create::<ipc::Service>().map_err(|e| IpcError::WaitSet(super::in_words(&e)))
}

/// Why [`run_waitset`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LoopEnd {
    /// SIGTERM or SIGINT.
    TerminationRequest,
    /// The callback returned `CallbackProgression::Stop`.
    Stopped,
}

/// How a [`run_waitset`] loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoopExit {
    /// Why.
    pub end: LoopEnd,
    /// Interrupted waits that were resumed (SIGSTOP/SIGCONT and the like).
    pub interrupts: u64,
}

/// Run the WaitSet until a termination signal or until `on_event` returns `Stop`. `Interrupt` (EINTR, e.g. after
/// SIGSTOP/SIGCONT) resumes waiting; a SIGTERM/SIGINT that caused it shows up as `TerminationRequest` on the next
/// wait, which ends the loop.
pub fn run_waitset<F>(waitset: &WaitSet<ipc::Service>, mut on_event: F) -> Result<LoopExit, IpcError>
where
    F: FnMut(WaitSetAttachmentId<ipc::Service>) -> CallbackProgression,
{
    let mut interrupts = 0;
    loop {
        match waitset.wait_and_process(&mut on_event) {
            Ok(WaitSetRunResult::Interrupt) => interrupts += 1,
            Ok(WaitSetRunResult::AllEventsHandled) => {}
            Ok(WaitSetRunResult::TerminationRequest) => {
                return Ok(LoopExit { end: LoopEnd::TerminationRequest, interrupts });
            }
            Ok(WaitSetRunResult::StopRequest) => return Ok(LoopExit { end: LoopEnd::Stopped, interrupts }),
            Err(e) => return Err(IpcError::WaitSet(super::in_words(&e))),
        }
    }
}

/// A periodic tick source a WaitSet can wait on alongside listeners: a `timerfd` on CLOCK_MONOTONIC with absolute
/// expirations on the [`clock::TickSchedule`] grid (not `WaitSet::attach_interval`, whose epoll timeout is rounded
/// up to whole milliseconds, so its ticks land 0-1 ms late). Attach with `waitset.attach_notification(&timer)`;
/// in the callback, [`TickTimer::read_expirations`] re-arms readiness and says how many periods passed.
#[derive(Debug)]
pub struct TickTimer {
    fd: FileDescriptor,
    schedule: clock::TickSchedule,
}

impl TickTimer {
    /// Arm a timer whose expirations fall at `schedule.deadline_ns(k)` for k = 0, 1, 2, ...
    pub fn new(schedule: clock::TickSchedule) -> Result<Self, IpcError> {
        // Safety: plain syscalls with valid arguments; the fd is owned by `FileDescriptor` from here on.
        let raw = unsafe { libc::timerfd_create(libc::CLOCK_MONOTONIC, libc::TFD_NONBLOCK | libc::TFD_CLOEXEC) };
        if raw < 0 {
            return Err(IpcError::Timer(std::io::Error::last_os_error()));
        }
        let fd = FileDescriptor::new(raw)
            .ok_or_else(|| IpcError::Timer(std::io::Error::other("timerfd is not a valid descriptor")))?;
        let spec = libc::itimerspec {
            it_interval: clock::timespec_from_ns(schedule.period_ns),
            // An all-zero it_value would disarm the timer; tick 0 at t=0 cannot happen with CLOCK_MONOTONIC.
            it_value: clock::timespec_from_ns(schedule.t0_ns.max(1)),
        };
        let rc =
            unsafe { libc::timerfd_settime(fd.native_handle(), libc::TFD_TIMER_ABSTIME, &spec, std::ptr::null_mut()) };
        if rc != 0 {
            return Err(IpcError::Timer(std::io::Error::last_os_error()));
        }
        Ok(Self { fd, schedule })
    }

    /// The grid the timer fires on.
    pub fn schedule(&self) -> clock::TickSchedule {
        self.schedule
    }

    /// Periods expired since the last read (0 if none: the fd is non-blocking). More than 1 means ticks were missed.
    pub fn read_expirations(&self) -> Result<u64, IpcError> {
        let mut count: u64 = 0;
        loop {
            // Safety: reads at most 8 bytes into a u64 we own.
            let n = unsafe { libc::read(self.fd.native_handle(), (&mut count as *mut u64).cast(), size_of::<u64>()) };
            if n == size_of::<u64>() as isize {
                return Ok(count);
            }
            let err = std::io::Error::last_os_error();
            match err.kind() {
                std::io::ErrorKind::WouldBlock => return Ok(0),
                std::io::ErrorKind::Interrupted => continue,
                _ => return Err(IpcError::Timer(err)),
            }
        }
    }
}

impl FileDescriptorBased for TickTimer {
    fn file_descriptor(&self) -> &FileDescriptor {
        &self.fd
    }
}

impl SynchronousMultiplexing for TickTimer {}
