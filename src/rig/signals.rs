//! SIGTERM/SIGINT (and SIGHUP, a closed terminal or a dropped ssh session) as a flag, for the plant, whose loop
//! sleeps with `clock_nanosleep` rather than in an iceoryx2 WaitSet (which would otherwise own SIGTERM and SIGINT
//! and report them as a termination request), and for the launcher, which must write its report whatever ends it.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};

static TERMINATION_REQUESTED: AtomicBool = AtomicBool::new(false);
static TERMINATION_SIGNAL: AtomicI32 = AtomicI32::new(0);

extern "C" fn on_termination_signal(signal: libc::c_int) {
    TERMINATION_SIGNAL.store(signal, Ordering::SeqCst);
    TERMINATION_REQUESTED.store(true, Ordering::SeqCst);
}

/// Route SIGTERM, SIGINT and SIGHUP to a flag instead of killing the process, so its final report gets written.
/// SA_RESTART is off, so blocking calls return EINTR and the loop gets to look at the flag. A SIGHUP that is
/// ignored already stays ignored: `nohup` asked for that, and the launcher starts its processes so (see
/// [`ignore_hangup`]) that a terminal's hangup ends them through the launcher's SIGTERM, in order.
pub fn install_termination_flag() {
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe; sigaction is given a zeroed,
    // then filled, struct as it requires, and reading the current action first passes a null new action.
    unsafe {
        let mut action: libc::sigaction = std::mem::zeroed();
        action.sa_sigaction = on_termination_signal as *const () as usize;
        libc::sigemptyset(&mut action.sa_mask);
        action.sa_flags = 0;
        for signal in [libc::SIGTERM, libc::SIGINT] {
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
        let mut current: libc::sigaction = std::mem::zeroed();
        libc::sigaction(libc::SIGHUP, std::ptr::null(), &mut current);
        if current.sa_sigaction != libc::SIG_IGN {
            libc::sigaction(libc::SIGHUP, &action, std::ptr::null_mut());
        }
    }
}

/// Ignore SIGHUP from here on, across `exec` too: for a process the launcher starts (between fork and exec, so
/// async-signal-safe), which a terminal's hangup must not end behind the launcher's back.
pub fn ignore_hangup() {
    // SAFETY: signal(2) with SIG_IGN is async-signal-safe and has no preconditions.
    unsafe {
        libc::signal(libc::SIGHUP, libc::SIG_IGN);
    }
}

/// Whether SIGTERM, SIGINT or SIGHUP arrived since [`install_termination_flag`].
pub fn termination_requested() -> bool {
    TERMINATION_REQUESTED.load(Ordering::SeqCst)
}

/// The signal that asked for termination (SIGTERM, SIGINT or SIGHUP), if one did.
pub fn termination_signal() -> Option<libc::c_int> {
    termination_requested().then(|| TERMINATION_SIGNAL.load(Ordering::SeqCst))
}

/// The exit status a shell gives a process ended by `signal` (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP).
pub fn exit_status_for(signal: libc::c_int) -> u8 {
    (128 + signal).clamp(0, 255) as u8
}

/// SIGINT, SIGTERM or SIGHUP by name.
pub fn name(signal: libc::c_int) -> &'static str {
    match signal {
        libc::SIGINT => "SIGINT",
        libc::SIGTERM => "SIGTERM",
        libc::SIGHUP => "SIGHUP",
        _ => "a signal",
    }
}
