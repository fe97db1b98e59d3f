//! Arming a device that must be armed before it flies (Betaflight): the arm switch's set point is held low until
//! the device's arming-disable flags clear (read over MSP, [`super::msp`]), then raised to the scenario's value, so
//! the switch goes low to high after the flags clear, as Betaflight requires; the set points it must see low to arm
//! (the throttle) are held at 0 until it reports itself armed. Not armed within `within_s` of its (re)start, the
//! run fails naming the flags that kept it from arming, in words. After a restart of the device, the same again.

use super::layout::DeviceLayout;
use super::msp::{StatusWatch, flags_in_words};
use serde::Deserialize;
use silrig_flight::scenario::Scenario;
use std::net::SocketAddr;

/// `[arming]` of a layout file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmingOptions {
    /// The set point carrying the arm switch: held at 0 until the device's arming-disable flags clear.
    pub switch: String,
    /// Set points held at 0 until the device reports itself armed (Betaflight refuses to arm with the throttle up).
    #[serde(default)]
    pub low_until_armed: Vec<String>,
    /// The TCP port of the device's MSP (Betaflight's UART1 on 5761), on the layout's `address`.
    pub msp_port: u16,
    /// Armed within this many seconds of the device's (re)start, or the run fails naming its flags.
    pub within_s: f64,
}

/// Where arming stands.
pub struct Arming {
    options: ArmingOptions,
    device: String,
    watch: StatusWatch,
    /// (index into the bound set points, the scenario's value) of the switch, then of each held set point.
    switch: (usize, f64),
    held: Vec<(usize, f64)>,
    started_ns: Option<u64>,
    raised: bool,
    armed: bool,
}

impl Arming {
    /// Start reading the device's status; the set points are checked against the scenario.
    pub fn new(options: &ArmingOptions, layout: &DeviceLayout, scenario: &Scenario) -> Result<Self, String> {
        if !(options.within_s > 0.0 && options.within_s <= 3600.0) {
            return Err(format!("device `{}`: arming within_s must be within 0..3600 s", layout.name));
        }
        for name in std::iter::once(&options.switch).chain(&options.low_until_armed) {
            if scenario.setpoint.get(name).is_none() {
                return Err(format!(
                    "device `{}`: [arming] names the set point `{name}`, which the scenario does not give; add it \
                     under [setpoint]",
                    layout.name
                ));
            }
        }
        Ok(Self {
            options: options.clone(),
            device: layout.name.clone(),
            watch: StatusWatch::start(SocketAddr::new(layout.address, options.msp_port)),
            switch: (0, 0.0),
            held: Vec::new(),
            started_ns: None,
            raised: false,
            armed: false,
        })
    }

    /// Find the set points among those the layout was bound against (the scenario's `names` and `values`).
    pub fn bind(&mut self, names: &[String], values: &[f64]) -> Result<(), String> {
        let find = |name: &String| {
            let k =
                names.iter().position(|n| n == name).ok_or_else(|| format!("[arming] set point `{name}` not found"));
            k.map(|k| (k, values[k]))
        };
        self.switch = find(&self.options.switch)?;
        self.held = self.options.low_until_armed.iter().map(find).collect::<Result<_, _>>()?;
        Ok(())
    }

    /// Hold the switch and the held set points low while they must be, else at the scenario's values.
    pub fn hold(&self, setpoints: &mut [f64]) {
        let (index, value) = self.switch;
        setpoints[index] = if self.raised { value } else { 0.0 };
        for &(index, value) in &self.held {
            setpoints[index] = if self.armed { value } else { 0.0 };
        }
    }

    /// Raise the switch once the flags clear, note when the device says it is armed; an error, naming the flags,
    /// when it has not armed in time.
    pub fn check(&mut self, now_ns: u64) -> Result<(), String> {
        let started = *self.started_ns.get_or_insert(now_ns);
        if self.armed {
            return Ok(());
        }
        let latest = self.watch.latest();
        if let Some(status) = latest.status {
            self.raised |= status.arming_disabled == 0;
            self.armed = status.armed;
        }
        if self.armed || now_ns.saturating_sub(started) < (self.options.within_s * 1e9) as u64 {
            return Ok(());
        }
        let why = match (latest.status, latest.problem) {
            (Some(status), _) => format!("its arming-disable flags: {}", flags_in_words(status.arming_disabled)),
            (None, Some(problem)) => format!("its MSP on port {} never answered: {problem}", self.options.msp_port),
            (None, None) => format!("its MSP on port {} never answered", self.options.msp_port),
        };
        Err(format!("device `{}` did not arm within {} s; {why}", self.device, self.options.within_s))
    }

    /// The device restarted: lower the switch and the held set points, and arm it again.
    pub fn restart(&mut self, now_ns: u64) {
        self.watch.forget();
        (self.started_ns, self.raised, self.armed) = (Some(now_ns), false, false);
    }

    /// Whether the device has said it is armed.
    pub fn armed(&self) -> bool {
        self.armed
    }
}
