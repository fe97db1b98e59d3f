//! The fault plan: `[[faults]]` entries of a scenario and `--fault` flags of `silrig run`, in one type. Each fault
//! has a time, a target process and an action. Process faults (kill, term, stop) are carried out by the launcher
//! with signals; loop faults (delay, jitter, drop) by the target process itself; plant faults (sensor noise and
//! bias, actuator stuck, hard-over, rate-frozen) by the plant model, identically in `silrig sim` and the rig. Device
//! faults (a device over UDP killed, or one of the packets it is sent cut for a window) by the controller process
//! flying the device.

use crate::role::Role;
use serde::{Deserialize, Serialize};

/// What happens.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FaultAction {
    /// SIGKILL (optionally restarted after `restart_after_s`).
    Kill,
    /// SIGTERM (optionally restarted after `restart_after_s`).
    Term,
    /// SIGSTOP, then SIGCONT after `duration_s`.
    Stop,
    /// The target sleeps `delay_ms` inside its loop, once or every `every_ticks` ticks.
    Delay,
    /// A random extra delay up to `max_us` each tick, for `duration_s` (default: to the end).
    Jitter,
    /// The target skips publishing for `ticks` ticks, or each tick with `probability`, for `duration_s`.
    Drop,
    /// Gaussian noise of `std` on the measured `channel` (plant only).
    SensorNoise,
    /// A constant `bias` on the measured `channel` (plant only).
    SensorBias,
    /// The `surface` stays where it is (plant only).
    ActuatorStuck,
    /// The `surface` goes to its `limit` ("min" or "max") at its rate limit (plant only).
    ActuatorHardOver,
    /// The `surface` cannot move (rate 0) while its command changes; like stuck, but named after the cause
    /// (a frozen rate channel). Kept separate so reports name what was injected (plant only).
    ActuatorRateFrozen,
    /// The device's `packet` (one the rig sends it, e.g. Betaflight's RC) is not sent for `duration_s` (device
    /// only): a receiver losing its link.
    Cut,
}

impl FaultAction {
    /// Name as in plans.
    pub fn label(self) -> &'static str {
        match self {
            FaultAction::Kill => "kill",
            FaultAction::Term => "term",
            FaultAction::Stop => "stop",
            FaultAction::Delay => "delay",
            FaultAction::Jitter => "jitter",
            FaultAction::Drop => "drop",
            FaultAction::SensorNoise => "sensor-noise",
            FaultAction::SensorBias => "sensor-bias",
            FaultAction::ActuatorStuck => "actuator-stuck",
            FaultAction::ActuatorHardOver => "actuator-hard-over",
            FaultAction::ActuatorRateFrozen => "actuator-rate-frozen",
            FaultAction::Cut => "cut",
        }
    }

    /// A signal to a process (the launcher's to a rig process, the controller's to its device's program).
    pub fn is_process_fault(self) -> bool {
        matches!(self, FaultAction::Kill | FaultAction::Term | FaultAction::Stop)
    }

    /// Carried out by the plant model (and so by `silrig sim` too).
    pub fn is_plant_model_fault(self) -> bool {
        matches!(
            self,
            FaultAction::SensorNoise
                | FaultAction::SensorBias
                | FaultAction::ActuatorStuck
                | FaultAction::ActuatorHardOver
                | FaultAction::ActuatorRateFrozen
        )
    }

    const ALL: [FaultAction; 12] = [
        FaultAction::Kill,
        FaultAction::Term,
        FaultAction::Stop,
        FaultAction::Delay,
        FaultAction::Jitter,
        FaultAction::Drop,
        FaultAction::SensorNoise,
        FaultAction::SensorBias,
        FaultAction::ActuatorStuck,
        FaultAction::ActuatorHardOver,
        FaultAction::ActuatorRateFrozen,
        FaultAction::Cut,
    ];
}

/// What a fault targets: one of the rig's processes, or the plant-side bridge of a run whose controller is on
/// another host (`silrig run --bridge-listen`), which the launcher starts and restarts like a process of the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FaultTarget {
    /// The plant.
    Plant,
    /// The controller.
    Controller,
    /// The logger.
    Logger,
    /// The plant-side bridge (process faults only).
    Bridge,
    /// The controller's device over UDP (`[controller] device`): its program killed, or a packet to it cut, by the
    /// controller process that flies it.
    Device,
}

impl FaultTarget {
    /// Every target, as plans name them.
    pub const ALL: [FaultTarget; 5] =
        [FaultTarget::Plant, FaultTarget::Controller, FaultTarget::Logger, FaultTarget::Bridge, FaultTarget::Device];

    /// Name in plans, reports and events.
    pub fn label(self) -> &'static str {
        match (self.role(), self) {
            (Some(role), _) => role.label(),
            (None, FaultTarget::Device) => "device",
            (None, _) => "bridge",
        }
    }

    /// Whether `silrig run` carries out the fault with a signal: a process fault of a rig process or the bridge (a
    /// device's program is the controller process's child, which kills it itself).
    pub fn signalled_by_launcher(self, action: FaultAction) -> bool {
        action.is_process_fault() && self != FaultTarget::Device
    }

    /// The rig process targeted; None for the bridge and the device.
    pub fn role(self) -> Option<Role> {
        match self {
            FaultTarget::Plant => Some(Role::Plant),
            FaultTarget::Controller => Some(Role::Controller),
            FaultTarget::Logger => Some(Role::Logger),
            FaultTarget::Bridge | FaultTarget::Device => None,
        }
    }
}

impl PartialEq<Role> for FaultTarget {
    fn eq(&self, role: &Role) -> bool {
        self.role() == Some(*role)
    }
}

impl std::fmt::Display for FaultTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

/// The F-16's channels a sensor fault can hit (its state as the plant measures it); on a plant of your own a
/// sensor fault names one of its outputs.
pub const SENSOR_CHANNELS: [&str; 10] =
    ["vt_fps", "alpha_rad", "beta_rad", "phi_rad", "theta_rad", "psi_rad", "p_radps", "q_radps", "r_radps", "alt_ft"];
/// Largest sensor noise (std) or |bias|, in the channel's unit (rad, rad/s, ft/s, ft): beyond any real sensor.
pub const MAX_SENSOR_ERROR: f64 = 1000.0;
/// The F-16's surfaces an actuator fault can hit; on a plant of your own an actuator fault names one of its
/// inputs.
pub const SURFACES: [&str; 3] = ["aileron", "elevator", "rudder"];

/// One fault of the plan. Which optional keys apply depends on `action`; [`Fault::validate`] checks that exactly
/// the right ones are given.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Fault {
    /// When, s of simulated time from the start of the run.
    pub at_s: f64,
    /// Which process.
    pub target: Option<FaultTarget>,
    /// What happens.
    pub action: Option<FaultAction>,
    /// Length of a stop, or of a delay/jitter/drop/sensor/actuator window (default: to the end of the run), s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub duration_s: Option<f64>,
    /// kill, term: start the process again this long after, s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart_after_s: Option<f64>,
    /// delay: how long the target sleeps inside its loop, ms.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub delay_ms: Option<f64>,
    /// delay: repeat every this many ticks (default: once).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every_ticks: Option<u64>,
    /// jitter: largest extra delay per tick, µs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_us: Option<f64>,
    /// drop: skip publishing this many consecutive ticks.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ticks: Option<u64>,
    /// drop: skip each tick with this probability (within `duration_s`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probability: Option<f64>,
    /// sensor faults: the measured channel (the F-16: one of [`SENSOR_CHANNELS`]; a plant of your own: an output).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub channel: Option<String>,
    /// sensor-noise: standard deviation, in the channel's unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub std: Option<f64>,
    /// sensor-bias: offset, in the channel's unit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bias: Option<f64>,
    /// actuator faults: the actuator (the F-16: "aileron", "elevator" or "rudder"; a plant of your own: an input).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<String>,
    /// actuator-hard-over: "min" or "max".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit: Option<String>,
    /// cut: the name of the device's packet not sent (a `[[to_device]]` packet of its layout, e.g. "rc").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub packet: Option<String>,
}

impl Fault {
    /// The target (validated faults always have one).
    pub fn target(&self) -> FaultTarget {
        self.target.unwrap_or(FaultTarget::Plant)
    }

    /// The action (validated faults always have one).
    pub fn action(&self) -> FaultAction {
        self.action.unwrap_or(FaultAction::Delay)
    }

    /// Whether the fault's window covers simulated time `t_s` (from `at_s` for `duration_s`, or to the end).
    pub fn active_at(&self, t_s: f64) -> bool {
        t_s >= self.at_s && self.duration_s.is_none_or(|d| t_s < self.at_s + d)
    }

    /// Short description, e.g. "controller kill at 3 s, restart after 0.5 s".
    pub fn describe(&self) -> String {
        let mut s = format!("{} {} at {} s", self.target().label(), self.action().label(), self.at_s);
        let mut add = |k: &str, v: Option<String>| {
            if let Some(v) = v {
                s += &format!(", {k} {v}");
            }
        };
        add("for", self.duration_s.map(|v| format!("{v} s")));
        add("restart after", self.restart_after_s.map(|v| format!("{v} s")));
        add("delay", self.delay_ms.map(|v| format!("{v} ms")));
        add("every", self.every_ticks.map(|v| format!("{v} ticks")));
        add("up to", self.max_us.map(|v| format!("{v} µs")));
        add("ticks", self.ticks.map(|v| v.to_string()));
        add("probability", self.probability.map(|v| v.to_string()));
        add("channel", self.channel.clone());
        add("std", self.std.map(|v| v.to_string()));
        add("bias", self.bias.map(|v| v.to_string()));
        add("surface", self.surface.clone());
        add("limit", self.limit.clone());
        add("packet", self.packet.clone());
        s
    }

    /// Check the fault against a run of `duration_s`; the error names the key and the problem.
    pub fn validate(&self, duration_s: f64) -> Result<(), (String, String)> {
        let Some(target) = self.target else {
            return refuse("target", "missing: plant, controller, logger, bridge or device".into());
        };
        let Some(action) = self.action else {
            let names: Vec<&str> = FaultAction::ALL.iter().map(|a| a.label()).collect();
            return refuse("action", format!("missing: one of {}", names.join(", ")));
        };
        if !(self.at_s >= 0.0 && self.at_s.is_finite()) {
            return refuse("at_s", format!("must be >= 0, got {}", self.at_s));
        }
        if self.at_s >= duration_s {
            return refuse("at_s", format!("{} s is beyond the run ({duration_s} s)", self.at_s));
        }
        self.check_keys_of(action)?;
        check_target_of(target, action)?;
        self.check_ranges(duration_s)?;
        if action == FaultAction::Drop {
            match (self.ticks, self.probability) {
                (None, None) | (Some(_), Some(_)) => {
                    return refuse("ticks", "drop needs either ticks or probability".into());
                }
                (Some(0), _) => return refuse("ticks", "must be >= 1".into()),
                (_, Some(p)) if !(p > 0.0 && p <= 1.0) => {
                    return refuse("probability", format!("must be in (0, 1], got {p}"));
                }
                _ => {}
            }
        }
        if let Some(l) = &self.limit
            && l != "min"
            && l != "max"
        {
            return refuse("limit", format!("must be \"min\" or \"max\", got {l:?}"));
        }
        Ok(())
    }

    /// Every key the action needs is given, and no key it does not use.
    fn check_keys_of(&self, action: FaultAction) -> Result<(), (String, String)> {
        let given: [(&str, bool); 13] = [
            ("duration_s", self.duration_s.is_some()),
            ("restart_after_s", self.restart_after_s.is_some()),
            ("delay_ms", self.delay_ms.is_some()),
            ("every_ticks", self.every_ticks.is_some()),
            ("max_us", self.max_us.is_some()),
            ("ticks", self.ticks.is_some()),
            ("probability", self.probability.is_some()),
            ("channel", self.channel.is_some()),
            ("std", self.std.is_some()),
            ("bias", self.bias.is_some()),
            ("surface", self.surface.is_some()),
            ("limit", self.limit.is_some()),
            ("packet", self.packet.is_some()),
        ];
        let (required, optional): (&[&str], &[&str]) = match action {
            // A device's program is started again by the controller's supervision as soon as it is seen dead.
            FaultAction::Kill if self.target == Some(FaultTarget::Device) => (&[], &[]),
            FaultAction::Kill | FaultAction::Term => (&[], &["restart_after_s"]),
            FaultAction::Stop => (&["duration_s"], &[]),
            FaultAction::Delay => (&["delay_ms"], &["every_ticks", "duration_s"]),
            FaultAction::Jitter => (&["max_us"], &["duration_s"]),
            FaultAction::Drop => (&[], &["ticks", "probability", "duration_s"]),
            FaultAction::SensorNoise => (&["channel", "std"], &["duration_s"]),
            FaultAction::SensorBias => (&["channel", "bias"], &["duration_s"]),
            FaultAction::ActuatorStuck | FaultAction::ActuatorRateFrozen => (&["surface"], &["duration_s"]),
            FaultAction::ActuatorHardOver => (&["surface", "limit"], &["duration_s"]),
            FaultAction::Cut => (&["packet", "duration_s"], &[]),
        };
        for (key, present) in given {
            if present && !required.contains(&key) && !optional.contains(&key) {
                return refuse(key, format!("does not apply to action \"{}\"", action.label()));
            }
            if !present && required.contains(&key) {
                return refuse(key, format!("is required for action \"{}\"", action.label()));
            }
        }
        Ok(())
    }

    /// The numbers within their ranges: positive where a zero means nothing, and below the bounds past which a
    /// value is a typo.
    fn check_ranges(&self, duration_s: f64) -> Result<(), (String, String)> {
        let positive = |k: &str, v: Option<f64>| match v {
            Some(x) if !(x > 0.0 && x.is_finite()) => refuse(k, format!("must be > 0, got {x}")),
            _ => Ok(()),
        };
        positive("duration_s", self.duration_s)?;
        positive("delay_ms", self.delay_ms)?;
        positive("max_us", self.max_us)?;
        positive("std", self.std)?;
        // Upper bounds: a window longer than the run, a stall longer than a second or noise beyond any sensor's
        // range is a typo, not a test.
        for (key, v, max) in [
            ("duration_s", self.duration_s, duration_s),
            ("restart_after_s", self.restart_after_s, duration_s),
            ("delay_ms", self.delay_ms, 1000.0),
            ("max_us", self.max_us, 1_000_000.0),
            ("std", self.std, MAX_SENSOR_ERROR),
            ("bias", self.bias.map(f64::abs), MAX_SENSOR_ERROR),
        ] {
            if let Some(x) = v
                && x > max
            {
                return refuse(key, format!("must be at most {max}, got {x}"));
            }
        }
        if let Some(r) = self.restart_after_s
            && !(r >= 0.0 && r.is_finite())
        {
            return refuse("restart_after_s", format!("must be >= 0, got {r}"));
        }
        if self.every_ticks == Some(0) {
            return refuse("every_ticks", "must be >= 1".into());
        }
        if let Some(b) = self.bias
            && !b.is_finite()
        {
            return refuse("bias", format!("must be finite, got {b}"));
        }
        Ok(())
    }
}

/// A fault refused: the key and the problem.
fn refuse(key: &str, problem: String) -> Result<(), (String, String)> {
    Err((key.to_string(), problem))
}

/// The action can happen to the target: the bridge is only a process, a drop needs a publisher the loop depends
/// on, and a fault in the plant model needs the plant.
fn check_target_of(target: FaultTarget, action: FaultAction) -> Result<(), (String, String)> {
    if (target == FaultTarget::Device) != matches!(action, FaultAction::Cut)
        && !(target == FaultTarget::Device && action == FaultAction::Kill)
    {
        return refuse(
            "target",
            format!(
                "the device can be killed or have a packet cut (`device:kill`, `device:cut`), and only the device \
                 can be cut; \"{}\" on {target} is neither",
                action.label()
            ),
        );
    }
    if target == FaultTarget::Bridge && !action.is_process_fault() {
        return refuse(
            "target",
            format!("the bridge can be killed, terminated or stopped; \"{}\" is not one of those", action.label()),
        );
    }
    if action == FaultAction::Drop && target == Role::Logger {
        return refuse("target", "drop needs a publisher the loop depends on: plant or controller".into());
    }
    if action.is_plant_model_fault() && target != Role::Plant {
        return refuse(
            "target",
            format!("action \"{}\" acts on the plant model: target must be plant", action.label()),
        );
    }
    Ok(())
}

impl Fault {
    /// Check that a sensor fault's `channel` is one of `channels` and an actuator fault's `surface` one of
    /// `surfaces`, the names `plant` measures and actuates (the F-16: [`SENSOR_CHANNELS`], [`SURFACES`]; a plant of
    /// your own: its outputs and inputs). On error (key, problem naming the list).
    pub fn check_names<S: AsRef<str>>(
        &self,
        plant: &str,
        channels: &[S],
        surfaces: &[S],
    ) -> Result<(), (String, String)> {
        let list = |names: &[S]| names.iter().map(|n| n.as_ref()).collect::<Vec<_>>().join(", ");
        if let Some(c) = &self.channel
            && !channels.iter().any(|n| n.as_ref() == c)
        {
            return Err(("channel".into(), format!("{plant} has no channel {c:?}; one of {}", list(channels))));
        }
        if let Some(s) = &self.surface
            && !surfaces.iter().any(|n| n.as_ref() == s)
        {
            return Err(("surface".into(), format!("{plant} has no actuator {s:?}; one of {}", list(surfaces))));
        }
        Ok(())
    }
}

/// Parse a `--fault` flag: `TARGET:ACTION@TIME[,KEY=VALUE...]`, e.g. `controller:kill@3s,restart_after=0.5s` or
/// `plant:delay@2s,delay=15ms`. Times and durations take `s`, `ms` or `us`; a bare number is seconds (for
/// `delay` milliseconds, for `max` microseconds). Keys: `for`/`duration`, `restart_after`, `delay`, `every`,
/// `max`, `ticks`, `p`/`probability`, `channel`, `std`, `bias`, `surface`, `limit`, `packet`; e.g.
/// `device:cut@12s,packet=rc,for=3s`.
pub fn parse_fault_flag(text: &str) -> Result<Fault, String> {
    let bad = |why: String| format!("--fault {text:?}: {why}");
    let (head, rest) = text.split_once('@').ok_or_else(|| bad("expected TARGET:ACTION@TIME".into()))?;
    let (target, action) = head.split_once(':').ok_or_else(|| bad("expected TARGET:ACTION before '@'".into()))?;
    let target = FaultTarget::ALL.into_iter().find(|r| r.label() == target.trim()).ok_or_else(|| {
        bad(format!("unknown target {:?}; plant, controller, logger, bridge or device", target.trim()))
    })?;
    let action = FaultAction::ALL.iter().copied().find(|a| a.label() == action.trim()).ok_or_else(|| {
        let actions: Vec<&str> = FaultAction::ALL.iter().map(|a| a.label()).collect();
        bad(format!("unknown action {:?}; the actions: {}", action.trim(), actions.join(", ")))
    })?;
    let mut parts = rest.split(',');
    let at = parts.next().unwrap_or("");
    let mut fault = Fault {
        at_s: parse_duration_s(at, 1.0).map_err(|e| bad(format!("time {at:?}: {e}")))?,
        target: Some(target),
        action: Some(action),
        ..Fault::default()
    };
    for kv in parts {
        let (k, v) = kv.split_once('=').ok_or_else(|| bad(format!("expected KEY=VALUE, got {kv:?}")))?;
        let (k, v) = (k.trim(), v.trim());
        let seconds = |unit| parse_duration_s(v, unit).map_err(|e| bad(format!("{k}: {e}")));
        let in_unit = |unit| parse_duration_in(v, unit).map_err(|e| bad(format!("{k}: {e}")));
        let number = || v.parse::<f64>().map_err(|_| bad(format!("{k}: not a number: {v:?}")));
        let count = || v.parse::<u64>().map_err(|_| bad(format!("{k}: not a whole number: {v:?}")));
        match k {
            "for" | "duration" => fault.duration_s = Some(seconds(1.0)?),
            "restart_after" => fault.restart_after_s = Some(seconds(1.0)?),
            "delay" => fault.delay_ms = Some(in_unit(1e-3)?),
            "every" => fault.every_ticks = Some(count()?),
            "max" => fault.max_us = Some(in_unit(1e-6)?),
            "ticks" => fault.ticks = Some(count()?),
            "p" | "probability" => fault.probability = Some(number()?),
            "channel" => fault.channel = Some(v.to_string()),
            "std" => fault.std = Some(number()?),
            "bias" => fault.bias = Some(number()?),
            "surface" => fault.surface = Some(v.to_string()),
            "limit" => fault.limit = Some(v.to_string()),
            "packet" => fault.packet = Some(v.to_string()),
            other => return Err(bad(format!("unknown key {other:?}"))),
        }
    }
    Ok(fault)
}

/// A duration with an optional unit (`s`, `ms`, `us`) in `unit_s` seconds, a bare number in that unit: `71ms` is
/// exactly 71 ms, not 0.071 s times 1000 (71.00000000000001, as fault descriptions then said).
fn parse_duration_in(text: &str, unit_s: f64) -> Result<f64, String> {
    let (v, scale) = parse_duration_parts(text, unit_s)?;
    // The units are powers of ten apart: their ratio as a whole number, so no rounding error of 1e-3 / 1e-6 enters.
    Ok(if scale >= unit_s { v * (scale / unit_s).round() } else { v / (unit_s / scale).round() })
}

/// A duration with an optional unit (`s`, `ms`, `us`); a bare number is in `bare_unit_s` seconds.
fn parse_duration_s(text: &str, bare_unit_s: f64) -> Result<f64, String> {
    let (v, scale) = parse_duration_parts(text, bare_unit_s)?;
    Ok(v * scale)
}

/// The number of a duration and its unit, s.
fn parse_duration_parts(text: &str, bare_unit_s: f64) -> Result<(f64, f64), String> {
    let t = text.trim();
    let (num, scale) = if let Some(n) = t.strip_suffix("ms") {
        (n, 1e-3)
    } else if let Some(n) = t.strip_suffix("us") {
        (n, 1e-6)
    } else if let Some(n) = t.strip_suffix('s') {
        (n, 1.0)
    } else {
        (t, bare_unit_s)
    };
    let v: f64 = num.trim().parse().map_err(|_| format!("not a duration: {text:?}"))?;
    if !v.is_finite() || v < 0.0 {
        return Err(format!("must be a finite duration >= 0, got {text:?}"));
    }
    Ok((v, scale))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delays_in_their_own_unit_are_exact() {
        let f = parse_fault_flag("controller:delay@5s,delay=71ms").unwrap();
        assert_eq!(f.delay_ms, Some(71.0));
        assert_eq!(parse_fault_flag("plant:jitter@1s,max=26000us,for=1s").unwrap().max_us, Some(26000.0));
        assert_eq!(parse_fault_flag("plant:jitter@1s,max=26ms,for=1s").unwrap().max_us, Some(26000.0));
        assert!(f.describe().contains("delay 71 ms"), "{}", f.describe());
        assert_eq!(parse_fault_flag("plant:delay@1s,delay=500us").unwrap().delay_ms, Some(0.5));
    }

    #[test]
    fn flags_parse_into_the_same_faults_as_plans() {
        let f = parse_fault_flag("controller:kill@3s,restart_after=0.5s").unwrap();
        assert_eq!(f.target, Some(FaultTarget::Controller));
        assert_eq!(f.action, Some(FaultAction::Kill));
        assert_eq!((f.at_s, f.restart_after_s), (3.0, Some(0.5)));
        let f = parse_fault_flag("plant:delay@2s,delay=15ms").unwrap();
        assert!((f.delay_ms.unwrap() - 15.0).abs() < 1e-9);
        let f = parse_fault_flag("logger:stop@1500ms,for=500ms").unwrap();
        assert!((f.at_s - 1.5).abs() < 1e-12 && (f.duration_s.unwrap() - 0.5).abs() < 1e-12);
        f.validate(10.0).unwrap();
        let f = parse_fault_flag("plant:jitter@1s,max=300us,for=2s").unwrap();
        assert!((f.max_us.unwrap() - 300.0).abs() < 1e-9);
        let f = parse_fault_flag("plant:actuator-hard-over@2s,surface=elevator,limit=min").unwrap();
        f.validate(10.0).unwrap();
    }

    #[test]
    fn bad_flags_and_plans_name_the_problem() {
        assert!(parse_fault_flag("pilot:kill@1s").unwrap_err().contains("unknown target \"pilot\""));
        let unknown = parse_fault_flag("plant:explode@1s").unwrap_err();
        assert!(unknown.contains("unknown action \"explode\"; the actions: kill, term, stop,"), "{unknown}");
        assert!(parse_fault_flag("plant:kill").unwrap_err().contains("TARGET:ACTION@TIME"));
        assert!(parse_fault_flag("plant:kill@soon").unwrap_err().contains("not a duration"));
        assert!(parse_fault_flag("plant:kill@1s,colour=red").unwrap_err().contains("unknown key \"colour\""));
        let f = parse_fault_flag("controller:kill@30s").unwrap();
        assert!(f.validate(10.0).unwrap_err().1.contains("beyond the run"));
        let f = parse_fault_flag("controller:stop@1s").unwrap();
        assert_eq!(f.validate(10.0).unwrap_err().0, "duration_s");
        let f = parse_fault_flag("controller:kill@1s,delay=5ms").unwrap();
        assert!(f.validate(10.0).unwrap_err().1.contains("does not apply to action \"kill\""));
        let f = parse_fault_flag("controller:sensor-bias@1s,channel=phi_rad,bias=0.1").unwrap();
        assert!(f.validate(10.0).unwrap_err().1.contains("target must be plant"));
        let f = parse_fault_flag("plant:sensor-bias@1s,channel=roll,bias=0.1").unwrap();
        f.validate(10.0).unwrap();
        let e = f.check_names("the F-16", &SENSOR_CHANNELS, &SURFACES).unwrap_err();
        assert_eq!(e.0, "channel");
        assert!(e.1.contains("the F-16 has no channel \"roll\"; one of vt_fps"), "{}", e.1);
        let f = parse_fault_flag("plant:drop@1s").unwrap();
        assert!(f.validate(10.0).unwrap_err().1.contains("either ticks or probability"));
        let f = parse_fault_flag("bridge:delay@1s,delay=5ms").unwrap();
        assert!(f.validate(10.0).unwrap_err().1.contains("the bridge can be killed, terminated or stopped"));
        let f = parse_fault_flag("bridge:stop@1s,for=0.5s").unwrap();
        assert_eq!(f.target, Some(FaultTarget::Bridge));
        f.validate(10.0).unwrap();
    }

    #[test]
    fn a_device_is_killed_or_has_a_packet_cut() {
        let f = parse_fault_flag("device:cut@12s,packet=rc,for=3s").unwrap();
        f.validate(30.0).unwrap();
        assert_eq!(
            (f.target, f.action, f.packet.as_deref()),
            (Some(FaultTarget::Device), Some(FaultAction::Cut), Some("rc"))
        );
        assert_eq!(f.describe(), "device cut at 12 s, for 3 s, packet rc");
        assert!(!FaultTarget::Device.signalled_by_launcher(FaultAction::Kill));
        assert!(FaultTarget::Controller.signalled_by_launcher(FaultAction::Kill));
        let f = parse_fault_flag("device:kill@5s").unwrap();
        f.validate(30.0).unwrap();
        // Its supervision restarts it at once; a cut needs its window and its packet; only the device is cut.
        let f = parse_fault_flag("device:kill@5s,restart_after=1s").unwrap();
        assert!(f.validate(30.0).unwrap_err().1.contains("does not apply to action \"kill\""));
        assert_eq!(parse_fault_flag("device:cut@5s,packet=rc").unwrap().validate(30.0).unwrap_err().0, "duration_s");
        assert_eq!(parse_fault_flag("device:cut@5s,for=1s").unwrap().validate(30.0).unwrap_err().0, "packet");
        let e = parse_fault_flag("controller:cut@5s,packet=rc,for=1s").unwrap().validate(30.0).unwrap_err();
        assert!(e.1.contains("only the device can be cut"), "{}", e.1);
        let e = parse_fault_flag("device:stop@5s,for=1s").unwrap().validate(30.0).unwrap_err();
        assert!(e.1.contains("the device can be killed or have a packet cut"), "{}", e.1);
    }

    #[test]
    fn windows_cover_their_duration() {
        let f = Fault { at_s: 1.0, duration_s: Some(0.5), ..Fault::default() };
        assert!(!f.active_at(0.99) && f.active_at(1.0) && f.active_at(1.49) && !f.active_at(1.5));
        let open = Fault { at_s: 1.0, ..Fault::default() };
        assert!(open.active_at(100.0));
    }
}
