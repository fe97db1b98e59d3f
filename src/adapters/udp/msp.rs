//! Betaflight's MultiWii Serial Protocol (MSP v1) over TCP, as far as arming and watching the flight need it:
//! `MSP_STATUS_EX` (150) read for the PID loop's cycle time, the flight modes active and the arming-disable flags,
//! named as `src/main/fc/runtime_config.h` names them, with what each means in words. The status numbers its flight
//! modes by the boxes the firmware has enabled, so `MSP_BOXIDS` (119) is read once per connection to turn them into
//! the boxes' permanent ids (ARM 0, ANGLE 1, ALTHOLD 3, FAILSAFE 27: `src/main/msp/msp_box.c`). [`StatusWatch`]
//! reads it on a thread of its own every 100 ms, so the control loop never waits on TCP.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// `MSP_STATUS_EX`.
const MSP_STATUS_EX: u8 = 150;
/// `MSP_BOXIDS`: the permanent id of each enabled box, in the order the status numbers them.
const MSP_BOXIDS: u8 = 119;

/// The flight modes' boxes by permanent id (`msp_box.c`), as the events name them; `FAILSAFE` is Betaflight's own
/// failsafe having engaged (its flight mode), not a switch.
pub const FLIGHT_MODES: [(u8, &str); 10] = [
    (0, "ARM"),
    (1, "ANGLE"),
    (2, "HORIZON"),
    (3, "ALTHOLD"),
    (5, "MAG"),
    (6, "HEADFREE"),
    (11, "POSHOLD"),
    (12, "PASSTHRU"),
    (27, "FAILSAFE"),
    (46, "GPS RESCUE"),
];
/// The permanent id of ARM.
pub const BOX_ARM: u8 = 0;
/// The permanent id of FAILSAFE.
pub const BOX_FAILSAFE: u8 = 27;

/// The flight modes set in `modes` (a bit per permanent id), by name: "ARM ANGLE"; "none" when none is.
pub fn modes_in_words(modes: u64) -> String {
    let set: Vec<&str> = FLIGHT_MODES.iter().filter(|(id, _)| modes & (1 << id) != 0).map(|(_, n)| *n).collect();
    let known = FLIGHT_MODES.iter().fold(0u64, |m, (id, _)| m | 1 << id);
    let mut words = if set.is_empty() { "none".to_string() } else { set.join(" ") };
    for id in (0..64).filter(|id| modes & !known & (1u64 << id) != 0) {
        words += &format!(" box{id}");
    }
    words
}

/// The arming-disable flags set in `flags`, by name only: "RX_FAILSAFE CALIBRATING"; "none" when none is.
pub fn flag_names(flags: u32) -> String {
    let set: Vec<&str> =
        ARMING_DISABLE_FLAGS.iter().enumerate().filter(|(bit, _)| flags & (1 << bit) != 0).map(|(_, f)| f.0).collect();
    if set.is_empty() { "none".to_string() } else { set.join(" ") }
}

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
    /// The flight modes active, a bit per box permanent id ([`FLIGHT_MODES`]); ARM among them.
    pub modes: u64,
}

impl Status {
    /// Whether the box of permanent id `id` is active.
    pub fn mode(&self, id: u8) -> bool {
        self.modes & (1 << id) != 0
    }
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
/// `box_ids`: `MSP_BOXIDS`'s reply, the permanent id of each of the first 32 boxes' bits.
pub fn parse_status(p: &[u8], box_ids: &[u8]) -> Option<Status> {
    let u16_at = |k: usize| Some(u16::from_le_bytes(p.get(k..k + 2)?.try_into().ok()?));
    let u32_at = |k: usize| Some(u32::from_le_bytes(p.get(k..k + 4)?.try_into().ok()?));
    let boxes = u32_at(6)?;
    let extra = *p.get(15)? as usize;
    let flags_at = 16 + extra + 1;
    let modes = box_ids
        .iter()
        .take(32)
        .enumerate()
        .filter(|&(bit, &id)| boxes & (1 << bit) != 0 && id < 64)
        .fold(0u64, |m, (_, &id)| m | 1 << id);
    Some(Status { cycle_us: u16_at(0)?, armed: boxes & 1 != 0, arming_disabled: u32_at(flags_at)?, modes })
}

/// The newest status read, or why there is none.
#[derive(Debug, Clone, Default)]
pub struct Latest {
    /// The newest status, if one was read since the last [`StatusWatch::forget`].
    pub status: Option<Status>,
    /// When it was read, CLOCK_MONOTONIC ns.
    pub read_ns: u64,
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
            // The boxes' permanent ids, read once per connection (they change only with the firmware's settings).
            let mut box_ids: Option<Vec<u8>> = None;
            while !stopping.load(Ordering::Relaxed) {
                let read = match stream.as_mut() {
                    None => Err("not connected".into()),
                    Some(s) => match &box_ids {
                        Some(ids) => read_status(s, ids),
                        None => ask(s, MSP_BOXIDS).and_then(|ids| read_status(s, box_ids.insert(ids))),
                    },
                };
                // Held only to store what was read: the control loop reads it every tick.
                let failed = {
                    let mut latest = shared.lock().unwrap_or_else(|e| e.into_inner());
                    match read {
                        Ok(status) => {
                            (latest.status, latest.problem) = (Some(status), None);
                            latest.read_ns = silrig_wire::clock::monotonic_ns();
                        }
                        Err(why) => latest.problem = Some(why),
                    }
                    latest.problem.is_some()
                };
                if failed {
                    box_ids = None;
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

fn read_status(stream: &mut TcpStream, box_ids: &[u8]) -> Result<Status, String> {
    let payload = ask(stream, MSP_STATUS_EX)?;
    parse_status(&payload, box_ids).ok_or_else(|| "an MSP_STATUS_EX reply too short to read".into())
}

/// Send `command` without a payload and wait for its reply's payload.
fn ask(stream: &mut TcpStream, command: u8) -> Result<Vec<u8>, String> {
    stream.write_all(&request(command, &[])).map_err(|e| e.to_string())?;
    let mut bytes = Vec::new();
    let mut chunk = [0u8; 512];
    loop {
        let n = stream.read(&mut chunk).map_err(|e| format!("no reply to MSP command {command}: {e}"))?;
        if n == 0 {
            return Err("it closed the MSP connection".into());
        }
        bytes.extend_from_slice(&chunk[..n]);
        if let Some(payload) = reply(&bytes, command) {
            return Ok(payload.to_vec());
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
        // The first two boxes enabled are ARM (0) and ANGLE (1); bit 1 set is ANGLE active.
        let status = parse_status(reply(&frame, 150).unwrap(), &[0, 1, 36]).unwrap();
        let flags = (1 << 12) | (1 << 28);
        assert_eq!(status, Status { cycle_us: 125, armed: true, arming_disabled: flags, modes: 0b11 });
        // The bits name the boxes the firmware enabled, in its order: here bit 1 is FAILSAFE.
        let status = parse_status(reply(&frame, 150).unwrap(), &[0, 27]).unwrap();
        assert!(status.mode(BOX_FAILSAFE) && status.mode(BOX_ARM) && !status.mode(1));
        assert_eq!(modes_in_words(status.modes), "ARM FAILSAFE");
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
        assert_eq!(flag_names((1 << 1) | (1 << 2)), "FAILSAFE RX_FAILSAFE");
        assert_eq!(flag_names(0), "none");
        assert_eq!(modes_in_words(0), "none");
        assert_eq!(modes_in_words((1 << 1) | (1 << 3) | (1 << 40)), "ANGLE ALTHOLD box40");
    }
}
