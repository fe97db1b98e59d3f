//! A process kept warm for a campaign: started once by a sweep's rig, it forks one flight after another from the
//! state it is in when it first opens a session, so each flight starts exactly as a fresh process would at that
//! point (the interpreter started, the modules imported, the libraries loaded), and nothing a flight does reaches
//! the next. The rig processes (`silrig-plant`, `silrig-logger`, `silrig-controller`) call [`serve_flights`] first
//! thing; the sessions a controller or plant of the user's own opens (the C ABI, the Python package) call it
//! before they read the run's variables, so the user's code changes nothing.
//!
//! The protocol, over the `SOCK_SEQPACKET` socket whose descriptor is in [`WARM_FD_ENV`] (one message each):
//! the process says `ready`; the sweep sends one request per flight, a JSON object `{"argv": [...], "env":
//! [[name, value], ...], "pdeathsig": n}` with the descriptor its output goes to (`SCM_RIGHTS`); the process forks,
//! says `started <pid>`, and when the flight has ended `exited <pid> <wait status>`. The flight child sets the
//! request's variables (every other `SILRIG_*` variable removed), its output, its own process group and its death
//! with the warm process, and goes on as the process the request describes. A closed socket ends the warm
//! process. Without [`WARM_FD_ENV`] nothing changes: the process flies one run as it always has.

use std::ffi::OsString;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd, RawFd};

/// The variable naming the descriptor of a warm process's socket; set by a sweep's warm rig only.
pub const WARM_FD_ENV: &str = "SILRIG_WARM_FD";
/// Set in every flight a warm process forks: the flight's launcher is the sweep, not its parent process.
pub const WARM_FLIGHT_ENV: &str = "SILRIG_WARM_FLIGHT";

/// Largest request, bytes: a command line and the run's variables.
pub const MAX_REQUEST_BYTES: usize = 64 * 1024;

/// One flight as the sweep asks for it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FlightRequest {
    /// The command line the flight runs with (`argv[0]` included): what a rig binary parses its arguments from.
    pub argv: Vec<String>,
    /// The run's variables (`SILRIG_*`), set in the flight in place of every `SILRIG_*` variable the warm process
    /// has.
    pub env: Vec<(String, String)>,
    /// The signal the flight gets when the warm process dies (`PR_SET_PDEATHSIG`).
    pub pdeathsig: i32,
}

/// Whether this process is a flight a warm process forked.
pub fn is_flight() -> bool {
    std::env::var_os(WARM_FLIGHT_ENV).is_some()
}

/// With [`WARM_FD_ENV`] set, become the warm process: serve flights until the sweep closes the socket (then
/// exit), returning only in each flight's child, with the flight's command line. Without it, `None`: fly as
/// always. A socket that cannot be used ends the process with the reason on stderr, since the sweep that set it
/// waits for `ready`.
pub fn serve_flights() -> Option<Vec<OsString>> {
    let fd: RawFd = std::env::var(WARM_FD_ENV).ok()?.parse().ok()?;
    // SAFETY: the descriptor was handed to this process for this use alone (the sweep's socket); it is owned here.
    let socket = unsafe { OwnedFd::from_raw_fd(fd) };
    // SAFETY: removing a variable while no other thread runs (the first thing a warm process does).
    unsafe { std::env::remove_var(WARM_FD_ENV) };
    match serve(&socket) {
        Ok(Some(argv)) => Some(argv),
        Ok(None) => std::process::exit(0),
        Err(e) => {
            eprintln!("silrig: warm process: {e}; ending");
            std::process::exit(2)
        }
    }
}

/// The warm process's loop; `Ok(Some(argv))` in a flight's child, `Ok(None)` when the sweep closed the socket.
fn serve(socket: &OwnedFd) -> Result<Option<Vec<OsString>>, String> {
    send(socket, b"ready").map_err(|e| format!("saying ready: {e}"))?;
    loop {
        let Some((text, output)) = receive(socket).map_err(|e| format!("reading a request: {e}"))? else {
            return Ok(None);
        };
        let request: FlightRequest =
            serde_json::from_slice(&text).map_err(|e| format!("a request that is not a flight: {e}"))?;
        let warm_pid = std::process::id() as libc::pid_t;
        // SAFETY: this process runs one thread (a warm process forks before it starts any), so the child may run
        // anything the parent could.
        let pid = unsafe { libc::fork() };
        if pid < 0 {
            return Err(format!("fork failed: {}", std::io::Error::last_os_error()));
        }
        if pid == 0 {
            // The socket closes when the caller drops it, on the way back to the flight's code.
            become_flight(&request, output, warm_pid);
            return Ok(Some(request.argv.into_iter().map(OsString::from).collect()));
        }
        drop(output);
        send(socket, format!("started {pid}").as_bytes()).map_err(|e| format!("saying started: {e}"))?;
        let mut status = 0;
        // SAFETY: waitpid on our own child, with a valid pointer to the status.
        while unsafe { libc::waitpid(pid, &mut status, 0) } < 0 {
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(format!("waiting for flight {pid}: {e}"));
            }
        }
        send(socket, format!("exited {pid} {status}").as_bytes()).map_err(|e| format!("saying exited: {e}"))?;
    }
}

/// In the flight's child: its own process group (a stop reaches whatever it starts), its death with the warm
/// process, its output, and the request's variables in place of the warm process's `SILRIG_*` ones.
fn become_flight(request: &FlightRequest, output: Option<OwnedFd>, warm_pid: libc::pid_t) {
    // SAFETY: setpgid, prctl, getppid, raise and dup2 on descriptors this process owns; one thread runs.
    unsafe {
        libc::setpgid(0, 0);
        libc::prctl(libc::PR_SET_PDEATHSIG, request.pdeathsig as libc::c_ulong, 0, 0, 0);
        // The warm process may have died between fork and prctl: then the signal never comes, so send it now.
        if libc::getppid() != warm_pid {
            libc::raise(request.pdeathsig);
        }
        if let Some(output) = output {
            libc::dup2(output.as_raw_fd(), 1);
            libc::dup2(output.as_raw_fd(), 2);
        }
    }
    let ours: Vec<OsString> = std::env::vars_os()
        .map(|(name, _)| name)
        .filter(|name| name.to_str().is_some_and(|n| n.starts_with("SILRIG_") && n != "SILRIG_CLIENT_LIB"))
        .collect();
    // SAFETY: the child runs one thread.
    unsafe {
        for name in ours {
            std::env::remove_var(name);
        }
        for (name, value) in &request.env {
            std::env::set_var(name, value);
        }
        std::env::set_var(WARM_FLIGHT_ENV, "1");
    }
}

/// Send one message on a `SOCK_SEQPACKET` socket.
pub fn send(socket: &OwnedFd, message: &[u8]) -> std::io::Result<()> {
    send_with_fd(socket, message, None)
}

/// Send one message, with a descriptor (`SCM_RIGHTS`) when given.
pub fn send_with_fd(socket: &OwnedFd, message: &[u8], fd: Option<RawFd>) -> std::io::Result<()> {
    let mut iov = libc::iovec { iov_base: message.as_ptr() as *mut libc::c_void, iov_len: message.len() };
    // u64 elements keep the control buffer aligned for cmsghdr.
    let mut control = [0u64; 8];
    // SAFETY: msghdr is plain data, zeroed then filled; CMSG_* walk the control buffer above, which is large
    // enough for one descriptor; sendmsg reads what the header points to.
    unsafe {
        let mut msg: libc::msghdr = std::mem::zeroed();
        msg.msg_iov = &mut iov;
        msg.msg_iovlen = 1;
        if let Some(fd) = fd {
            msg.msg_control = control.as_mut_ptr() as *mut libc::c_void;
            msg.msg_controllen = libc::CMSG_SPACE(size_of::<RawFd>() as u32) as usize;
            let cmsg = libc::CMSG_FIRSTHDR(&msg);
            (*cmsg).cmsg_level = libc::SOL_SOCKET;
            (*cmsg).cmsg_type = libc::SCM_RIGHTS;
            (*cmsg).cmsg_len = libc::CMSG_LEN(size_of::<RawFd>() as u32) as usize;
            std::ptr::write_unaligned(libc::CMSG_DATA(cmsg) as *mut RawFd, fd);
        }
        loop {
            if libc::sendmsg(socket.as_raw_fd(), &msg, libc::MSG_NOSIGNAL) >= 0 {
                return Ok(());
            }
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(e);
            }
        }
    }
}

/// Receive one message and the descriptor it carries, if any; `None` when the other end closed the socket.
pub fn receive(socket: &OwnedFd) -> std::io::Result<Option<(Vec<u8>, Option<OwnedFd>)>> {
    let mut buffer = vec![0u8; MAX_REQUEST_BYTES];
    let mut iov = libc::iovec { iov_base: buffer.as_mut_ptr() as *mut libc::c_void, iov_len: buffer.len() };
    let mut control = [0u64; 8];
    // SAFETY: as in send_with_fd; recvmsg writes at most the lengths given, and a descriptor it passes is
    // taken into an OwnedFd once.
    unsafe {
        let mut msg: libc::msghdr = std::mem::zeroed();
        msg.msg_iov = &mut iov;
        msg.msg_iovlen = 1;
        msg.msg_control = control.as_mut_ptr() as *mut libc::c_void;
        msg.msg_controllen = std::mem::size_of_val(&control);
        let n = loop {
            let n = libc::recvmsg(socket.as_raw_fd(), &mut msg, libc::MSG_CMSG_CLOEXEC);
            if n >= 0 {
                break n as usize;
            }
            let e = std::io::Error::last_os_error();
            if e.kind() != std::io::ErrorKind::Interrupted {
                return Err(e);
            }
        };
        let mut fd = None;
        let cmsg = libc::CMSG_FIRSTHDR(&msg);
        if !cmsg.is_null() && (*cmsg).cmsg_level == libc::SOL_SOCKET && (*cmsg).cmsg_type == libc::SCM_RIGHTS {
            fd = Some(OwnedFd::from_raw_fd(std::ptr::read_unaligned(libc::CMSG_DATA(cmsg) as *const RawFd)));
        }
        if n == 0 && fd.is_none() {
            return Ok(None);
        }
        buffer.truncate(n);
        Ok(Some((buffer, fd)))
    }
}

/// A connected pair of `SOCK_SEQPACKET` sockets (close-on-exec): the sweep keeps one, a warm process gets the
/// other.
pub fn socket_pair() -> std::io::Result<(OwnedFd, OwnedFd)> {
    let mut fds = [0 as RawFd; 2];
    // SAFETY: socketpair writes two descriptors into the array on success; each is owned once.
    unsafe {
        if libc::socketpair(libc::AF_UNIX, libc::SOCK_SEQPACKET | libc::SOCK_CLOEXEC, 0, fds.as_mut_ptr()) < 0 {
            return Err(std::io::Error::last_os_error());
        }
        Ok((OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_message_and_its_descriptor_cross_the_socket() {
        let (a, b) = socket_pair().unwrap();
        let (reader, writer) = std::io::pipe().unwrap();
        send_with_fd(&a, b"hello", Some(writer.as_raw_fd())).unwrap();
        drop(writer);
        let (text, fd) = receive(&b).unwrap().unwrap();
        assert_eq!(text, b"hello");
        let mut passed = std::fs::File::from(fd.expect("a descriptor came"));
        use std::io::{Read, Write};
        passed.write_all(b"through").unwrap();
        drop(passed);
        let mut got = String::new();
        let mut reader = reader;
        reader.read_to_string(&mut got).unwrap();
        assert_eq!(got, "through");
        drop(a);
        assert!(receive(&b).unwrap().is_none(), "a closed socket reads as the end");
    }
}
