//! Betaflight's MultiWii Serial Protocol (MSP v1) over TCP, as far as arming needs it: `MSP_STATUS_EX` (150) read
//! for the PID loop's cycle time, the flight-mode boxes (ARM is box 0) and the arming-disable flags, named as
//! `src/main/fc/runtime_config.h` names them, with what each means in words. [`StatusWatch`] reads it on a thread
//! of its own every 100 ms, so the control loop never waits on TCP.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// `MSP_STATUS_EX`.
const MSP_STATUS_EX: u8 = 150;

/// Betaflight 4.6's arming-disable flags, bit by bit, with what each asks of the pilot (or the rig).
pub const ARMING_DISABLE_FLAGS: [(&str, &str); 29] = [
    ("NO_GYRO", "no gyro detected"),
    ("FAILSAFE", "failsafe is active"),
    ("RX_FAILSAFE", "no valid RC frames (the rig's RC packets are not reaching it)"),
    ("NOT_DISARMED", "the arm switch was not seen low since boot"),
    ("BOXFAILSAFE", "the failsafe switch is on"),
    ("RUNAWAY_TAKEOFF", "runaway take-off prevention tripped"),
    ("CRASH_DETECTED", "a crash was detected"),
    ("THROTTLE", "the throttle is not low"),
    ("ANGLE", "the craft is tilted beyond small_angle"),
    ("BOOT_GRACE_TIME", "it booted less than a few seconds ago"),
    ("NOPREARM", "the pre-arm switch is off"),
    ("LOAD", "its CPU load is too high"),
    ("CALIBRATING", "the gyro is calibrating: it needs a still, level craft"),
    ("CLI", "its CLI is open"),
    ("CMS_MENU", "its on-screen menu is open"),
    ("BST", "BST"),
    ("MSP", "arming was disabled over MSP"),
    ("PARALYZE", "paralyze mode"),
    ("GPS", "GPS rescue needs a fix"),
    ("RESC", "the rescue mode switch is on"),
    ("DSHOT_TELEM", "DShot telemetry is missing"),
    ("REBOOT_REQUIRED", "a setting needs a reboot"),
    ("DSHOT_BITBANG", "DShot bitbang is unavailable"),
    ("ACC_CALIBRATION", "the accelerometer is not calibrated"),
    ("MOTOR_PROTOCOL", "no motor protocol is configured"),
    ("CRASHFLIP", "crash-flip mode is on"),
    ("ALTHOLD", "the altitude-hold switch is on"),
    ("POSHOLD", "the position-hold switch is on"),
    ("ARM_SWITCH", "the arm switch was high when the other flags cleared (lower it, then raise it)"),
];

/// The flags set in `flags`, in words: "CALIBRATING (the gyro is calibrating ...), ...".
pub fn flags_in_words(flags: u32) -> String {
    let set: Vec<String> = ARMING_DISABLE_FLAGS
        .iter()
        .enumerate()
        .filter(|(bit, _)| flags & (1 << bit) != 0)
        .map(|(_, (name, meaning))| format!("{name} ({meaning})"))
        .collect();
    let unknown = flags & !((1u32 << ARMING_DISABLE_FLAGS.len()) - 1);
    let mut words = if set.is_empty() { "none".to_string() } else { set.join(", ") };
    if unknown != 0 {
        words += &format!(", unknown bits {unknown:#x}");
    }
    words
}

/// What `MSP_STATUS_EX` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Status {
    /// The PID loop's last cycle, µs.
    pub cycle_us: u16,
    /// Armed (flight-mode box 0).
    pub armed: bool,
    /// The arming-disable flags.
    pub arming_disabled: u32,
}

/// One MSP v1 request frame: `$M<`, size, command, payload, XOR checksum of size, command and payload.
pub fn request(command: u8, payload: &[u8]) -> Vec<u8> {
    let mut frame = b"$M<".to_vec();
    frame.push(payload.len() as u8);
    frame.push(command);
    frame.extend_from_slice(payload);
    frame.push(frame[3..].iter().fold(0, |a, b| a ^ b));
    frame
}

/// The payload of the first whole `$M>` reply to `command` in `bytes`, checksum checked.
pub fn reply(bytes: &[u8], command: u8) -> Option<&[u8]> {
    let mut at = 0;
    while let Some(start) = bytes[at..].windows(3).position(|w| w == b"$M>").map(|p| p + at) {
        let (size, cmd) = (*bytes.get(start + 3)? as usize, *bytes.get(start + 4)?);
        let end = start + 5 + size;
        let check = *bytes.get(end)?;
        if cmd == command && bytes[start + 3..end].iter().fold(0, |a, b| a ^ b) == check {
            return Some(&bytes[start + 5..end]);
        }
        at = start + 3;
    }
    None
}

/// `MSP_STATUS_EX`'s payload read: cycle (u16), i2c errors (u16), sensors (u16), boxes (u32), profile (u8), load
/// (u16), profile count (u8), rate profile (u8), more box bytes (u8 count, then them), flag count (u8), flags (u32).
pub fn parse_status(p: &[u8]) -> Option<Status> {
    let u16_at = |k: usize| Some(u16::from_le_bytes(p.get(k..k + 2)?.try_into().ok()?));
    let u32_at = |k: usize| Some(u32::from_le_bytes(p.get(k..k + 4)?.try_into().ok()?));
    let boxes = u32_at(6)?;
    let extra = *p.get(15)? as usize;
    let flags_at = 16 + extra + 1;
    Some(Status { cycle_us: u16_at(0)?, armed: boxes & 1 != 0, arming_disabled: u32_at(flags_at)? })
}

/// The newest status read, or why there is none.
#[derive(Debug, Clone, Default)]
pub struct Latest {
    /// The newest status, if one was read since the last [`StatusWatch::forget`].
    pub status: Option<Status>,
    /// The last problem reaching MSP.
    pub problem: Option<String>,
}

/// Reads `MSP_STATUS_EX` from `address` every 100 ms on a thread of its own, reconnecting as needed.
pub struct StatusWatch {
    latest: Arc<Mutex<Latest>>,
    stop: Arc<AtomicBool>,
}

impl StatusWatch {
    /// Start watching.
    pub fn start(address: SocketAddr) -> Self {
        let latest = Arc::new(Mutex::new(Latest::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let (shared, stopping) = (latest.clone(), stop.clone());
        std::thread::spawn(move || {
            let mut stream: Option<TcpStream> = None;
            while !stopping.load(Ordering::Relaxed) {
                let read = stream.as_mut().map(read_status).unwrap_or_else(|| Err("not connected".into()));
                // Held only to store what was read: the control loop reads it every tick.
                let failed = {
                    let mut latest = shared.lock().unwrap_or_else(|e| e.into_inner());
                    match read {
                        Ok(status) => (latest.status, latest.problem) = (Some(status), None),
                        Err(why) => latest.problem = Some(why),
                    }
                    latest.problem.is_some()
                };
                if failed {
                    stream = TcpStream::connect_timeout(&address, Duration::from_millis(500)).ok();
                    if let Some(s) = &stream {
                        let _ = s.set_read_timeout(Some(Duration::from_millis(500)));
                        // Betaflight's SITL loses what is sent at once after a connection: let it attach first.
                        std::thread::sleep(Duration::from_millis(300));
                    }
                }
                std::thread::sleep(Duration::from_millis(100));
            }
        });
        Self { latest, stop }
    }

    /// The newest status read.
    pub fn latest(&self) -> Latest {
        self.latest.lock().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Drop the status read so far (the device restarted: what it said before no longer holds).
    pub fn forget(&self) {
        self.latest.lock().unwrap_or_else(|e| e.into_inner()).status = None;
    }
}

impl Drop for StatusWatch {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

fn read_status(stream: &mut TcpStream) -> Result<Status, String> {
    stream.write_all(&request(MSP_STATUS_EX, &[])).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    let mut chunk = [0u8; 512];
    loop {
        let n = stream.read(&mut chunk).map_err(|e| format!("no MSP_STATUS_EX reply: {e}"))?;
        if n == 0 {
            return Err("it closed the MSP connection".into());
        }
        bytes.extend_from_slice(&chunk[..n]);
        if let Some(payload) = reply(&bytes, MSP_STATUS_EX) {
            return parse_status(payload).ok_or_else(|| "an MSP_STATUS_EX reply too short to read".into());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_request_frame_carries_the_xor_checksum() {
        // MSP_STATUS_EX with no payload: size 0 ^ command 150 = 150.
        assert_eq!(request(150, &[]), b"$M<\x00\x96\x96");
        assert_eq!(request(1, &[2, 3]), [b'$', b'M', b'<', 2, 1, 2, 3, 2 ^ 1 ^ 2 ^ 3]);
    }

    fn status_payload(cycle_us: u16, boxes: u32, extra: &[u8], flags: u32) -> Vec<u8> {
        let mut p = cycle_us.to_le_bytes().to_vec();
        p.extend_from_slice(&[0, 0, 0x21, 0]);
        p.extend_from_slice(&boxes.to_le_bytes());
        p.extend_from_slice(&[0, 5, 0, 4, 0]);
        p.push(extra.len() as u8);
        p.extend_from_slice(extra);
        p.push(29);
        p.extend_from_slice(&flags.to_le_bytes());
        p.push(0);
        p
    }

    #[test]
    fn a_status_reply_is_found_checked_and_read() {
        let payload = status_payload(125, 0b11, &[0, 0], (1 << 12) | (1 << 28));
        let mut frame = b"noise$M>".to_vec();
        frame.push(payload.len() as u8);
        frame.push(150);
        frame.extend_from_slice(&payload);
        frame.push(frame[8..].iter().fold(0, |a, b| a ^ b));
        let status = parse_status(reply(&frame, 150).unwrap()).unwrap();
        assert_eq!(status, Status { cycle_us: 125, armed: true, arming_disabled: (1 << 12) | (1 << 28) });
        // A corrupted checksum, another command or a cut frame is no reply.
        let mut bad = frame.clone();
        *bad.last_mut().unwrap() ^= 1;
        assert_eq!(reply(&bad, 150), None);
        assert_eq!(reply(&frame, 101), None);
        assert_eq!(reply(&frame[..frame.len() - 2], 150), None);
    }

    #[test]
    fn flags_are_named_in_words() {
        assert_eq!(flags_in_words(0), "none");
        let words = flags_in_words((1 << 12) | (1 << 7) | (1 << 30));
        assert!(
            words.starts_with("THROTTLE (the throttle is not low), CALIBRATING (the gyro is calibrating"),
            "{words}"
        );
        assert!(words.ends_with("unknown bits 0x40000000"), "{words}");
    }
}
