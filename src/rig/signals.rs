//! SIGTERM/SIGINT as a flag, for the plant, whose loop sleeps with `clock_nanosleep` rather than in an iceoryx2
//! WaitSet (which would otherwise own the signals and report them as a termination request).

use std::sync::atomic::{AtomicBool, Ordering};

static TERMINATION_REQUESTED: AtomicBool = AtomicBool::new(false);

extern "C" fn on_termination_signal(_: libc::c_int) {
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
