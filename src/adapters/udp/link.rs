//! The sockets of one device link: one socket sending every packet to the device, and one listening on each port
//! the device sends to, bound when the link opens so a port already in use is refused, by number and packet, before
//! anything flies. Waiting for a reply is one `poll` over the listening sockets up to a deadline, so the controller
//! sleeps rather than spins while the device (a SITL on the same two vCPUs) computes.

use super::layout::DeviceLayout;
use silrig_wire::clock::monotonic_ns;
use std::io::ErrorKind;
use std::net::{Ipv4Addr, SocketAddr, UdpSocket};
use std::os::fd::AsRawFd;

/// Larger than any packet a layout declares, so a packet of the wrong size arrives whole and is refused as such
/// rather than cut to the expected size.
const RECEIVE_BUFFER_BYTES: usize = 65_536;

/// The link's sockets.
#[derive(Debug)]
pub struct Link {
    sender: UdpSocket,
    /// One per packet from the device, in the layout's order.
    receivers: Vec<UdpSocket>,
    device: std::net::IpAddr,
    buffer: Vec<u8>,
}

impl Link {
    /// Bind a socket on each port the device sends to, and one to send from; a port in use is refused naming it.
    pub fn open(layout: &DeviceLayout) -> Result<Self, String> {
        let mut receivers = Vec::new();
        for packet in &layout.from_device {
            let at = SocketAddr::from((Ipv4Addr::UNSPECIFIED, packet.port));
            let socket = UdpSocket::bind(at).map_err(|e| {
                let why = if e.kind() == ErrorKind::AddrInUse {
                    "the port is in use by another program (another run, or the device itself listening there); \
                     stop it or give the device another port"
                        .to_string()
                } else {
                    e.to_string()
                };
                format!(
                    "device `{}`: cannot listen on UDP port {} for packet `{}`: {why}",
                    layout.name, packet.port, packet.name
                )
            })?;
            socket.set_nonblocking(true).map_err(|e| format!("device `{}`: {e}", layout.name))?;
            receivers.push(socket);
        }
        let sender = UdpSocket::bind((Ipv4Addr::UNSPECIFIED, 0))
            .map_err(|e| format!("device `{}`: cannot open a UDP socket to send from: {e}", layout.name))?;
        Ok(Self { sender, receivers, device: layout.address, buffer: vec![0; RECEIVE_BUFFER_BYTES] })
    }

    /// Send one packet to the device's `port`. A device not yet listening is not an error (UDP does not say so;
    /// its silence is judged from what comes back).
    pub fn send(&self, port: u16, bytes: &[u8]) -> std::io::Result<()> {
        match self.sender.send_to(bytes, (self.device, port)) {
            Err(e) if e.kind() == ErrorKind::ConnectionRefused => Ok(()),
            other => other.map(|_| ()),
        }
    }

    /// The next packet waiting on listening socket `k`, if any.
    pub fn try_receive(&mut self, k: usize) -> Option<&[u8]> {
        match self.receivers[k].recv(&mut self.buffer) {
            Ok(n) => Some(&self.buffer[..n]),
            Err(_) => None,
        }
    }

    /// How many sockets listen (one per packet from the device).
    pub fn receivers(&self) -> usize {
        self.receivers.len()
    }

    /// Sleep until a packet waits on any listening socket or the monotonic clock reaches `deadline_ns`; whether
    /// one waits.
    pub fn wait(&self, deadline_ns: u64) -> bool {
        let mut fds: Vec<libc::pollfd> = self
            .receivers
            .iter()
            .map(|s| libc::pollfd { fd: s.as_raw_fd(), events: libc::POLLIN, revents: 0 })
            .collect();
        loop {
            let now = monotonic_ns();
            if now >= deadline_ns {
                return false;
            }
            // poll's timeout is in ms: round up, so a deadline under 1 ms still sleeps rather than spins; the
            // caller checks the deadline again when it wakes.
            let timeout_ms = (deadline_ns - now).div_ceil(1_000_000).min(i32::MAX as u64) as i32;
            // SAFETY: `fds` is a live, correctly sized array of pollfd for the duration of the call.
            let ready = unsafe { libc::poll(fds.as_mut_ptr(), fds.len() as libc::nfds_t, timeout_ms) };
            if ready > 0 {
                return true;
            }
            if ready < 0 && std::io::Error::last_os_error().kind() != ErrorKind::Interrupted {
                return false;
            }
        }
    }
}
