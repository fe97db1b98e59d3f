//! SIGTERM/SIGINT as a flag, for the plant, whose loop sleeps with `clock_nanosleep` rather than in an iceoryx2
//! WaitSet (which would otherwise own the signals and report them as a termination request).

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

static TERMINATION_REQUESTED: AtomicBool = AtomicBool::new(false);
static TERMINATION_SIGNAL: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_termination_signal(signal: libc::c_int) {
    TERMINATION_SIGNAL.store(signal, Ordering::SeqCst);
    TERMINATION_REQUESTED.store(true, Ordering::SeqCst);
}

/// Route SIGTERM and SIGINT to a flag instead of killing the process, so its final report gets written.
/// SA_RESTART is off, so blocking calls return EINTR and the loop gets to look at the flag.
pub fn install_termination_flag() {
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe; sigaction is given a zeroed,
    // then filled, struct as it requires.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_termination_signal as *const () as usize;
        libc::sigemptyset(&mut action.sa_mask);
        action.sa_flags = 0;
        for signal in [libc::SIGTERM, libc::SIGINT] {
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
    }
}

/// Whether SIGTERM or SIGINT arrived since [`install_termination_flag`].
pub fn termination_requested() -> bool {
    TERMINATION_REQUESTED.load(Ordering::SeqCst)
}

/// The signal that asked for termination (SIGTERM or SIGINT), if one did.
pub fn termination_signal() -> Option<libc::c_int> {
    termination_requested().then(|| TERMINATION_SIGNAL.load(Ordering::SeqCst))
}

/// The exit status a shell gives a process ended by `signal` (130 for SIGINT, 143 for SIGTERM).
pub fn exit_status_for(signal: libc::c_int) -> u8 {
    (128 + signal).clamp(0, 255) as u8
}

/// SIGINT or SIGTERM by name.
pub fn name(signal: libc::c_int) -> &'static str {
    match signal {
        libc::SIGINT => "SIGINT",
        libc::SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}
