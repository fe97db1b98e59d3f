//! Binding a layout file to one plant: every name found, every type known, every scale, offset and frame the right
//! length, every port set once, refused in words naming the packet and field before anything flies.

use super::layout::{
    BoundLayout, BoundReceive, BoundSend, DeviceLayout, FieldLayout, LayoutError, PacketLayout, ReceiveGroup,
    ScalarType, SendField, SignalNames, Source, TYPE_NAMES,
};
use std::collections::BTreeSet;

/// Where a field sits, for messages: "packet `fdm`, field 3".
fn at(packet: &PacketLayout, k: usize) -> String {
    format!("packet `{}`, field {}", packet.name, k + 1)
}

fn scalar_type(packet: &PacketLayout, k: usize, field: &FieldLayout) -> Result<ScalarType, LayoutError> {
    ScalarType::parse(&field.ty).ok_or_else(|| {
        LayoutError(format!("{}: unknown type `{}`; the types are {TYPE_NAMES}", at(packet, k), field.ty))
    })
}

/// A scale or offset list as one value per field of a group of `n`.
fn per_field(
    packet: &PacketLayout,
    k: usize,
    what: &str,
    given: &Option<super::layout::OneOrMany<f64>>,
    n: usize,
    default: f64,
) -> Result<Vec<f64>, LayoutError> {
    let values = given.as_ref().map(|v| v.values()).unwrap_or_else(|| vec![default]);
    let values = if values.len() == 1 { vec![values[0]; n] } else { values };
    if values.len() != n {
        return Err(LayoutError(format!(
            "{}: {what} has {} values for {n} fields; give one for all or one per field",
            at(packet, k),
            values.len()
        )));
    }
    if let Some(bad) = values.iter().find(|v| !v.is_finite()) {
        return Err(LayoutError(format!("{}: {what} {bad} is not a finite number", at(packet, k))));
    }
    Ok(values)
}

fn check_frame(packet: &PacketLayout, k: usize, field: &FieldLayout, n: usize) -> Result<(), LayoutError> {
    match field.frame {
        Some(frame) if frame.width() != n => Err(LayoutError(format!(
            "{}: frame `{}` converts {} values, but the field group has {n}",
            at(packet, k),
            frame.name(),
            frame.width()
        ))),
        _ => Ok(()),
    }
}

/// What a sent name stands for.
fn source(names: &SignalNames, packet: &PacketLayout, k: usize, name: &str) -> Result<Source, LayoutError> {
    if name == "time_s" {
        return Ok(Source::Time);
    }
    if let Some(sp) = name.strip_prefix("setpoint.") {
        return names.setpoints.iter().position(|s| s == sp).map(Source::Setpoint).ok_or_else(|| {
            LayoutError(format!(
                "{}: the scenario has no set point `{sp}`; add it under [setpoint] (it has: {})",
                at(packet, k),
                listed(names.setpoints)
            ))
        });
    }
    names.outputs.iter().position(|s| s == name).map(Source::Output).ok_or_else(|| {
        LayoutError(format!(
            "{}: the plant has no output `{name}`; its outputs are: {} (or `time_s`, `setpoint.<name>`)",
            at(packet, k),
            listed(names.outputs)
        ))
    })
}

fn listed(names: &[String]) -> String {
    if names.is_empty() { "none".to_string() } else { names.join(", ") }
}

fn bind_send(names: &SignalNames, packet: &PacketLayout) -> Result<BoundSend, LayoutError> {
    let mut fields = Vec::new();
    for (k, field) in packet.fields.iter().enumerate() {
        let ty = scalar_type(packet, k, field)?;
        if field.to.is_some() || field.skip {
            return Err(LayoutError(format!("{}: `to` and `skip` are for packets from the device", at(packet, k))));
        }
        let sources: Vec<Source> = match (&field.from, field.value) {
            (Some(from), None) if field.count.is_none() => {
                from.values().iter().map(|n| source(names, packet, k, n)).collect::<Result<_, _>>()?
            }
            (None, Some(value)) if value.is_finite() => vec![Source::Constant(value); field.count.unwrap_or(1)],
            _ => {
                return Err(LayoutError(format!(
                    "{}: give either `from` (what it carries) or `value` (a finite constant, with `count` for \
                     several)",
                    at(packet, k)
                )));
            }
        };
        let n = sources.len();
        check_frame(packet, k, field, n)?;
        let scale = per_field(packet, k, "scale", &field.scale, n, 1.0)?;
        let offset = per_field(packet, k, "offset", &field.offset, n, 0.0)?;
        let matrix = field.frame.map(|f| f.matrix());
        for i in 0..n {
            let terms = match &matrix {
                Some(m) => sources.iter().zip(&m[i]).filter(|(_, c)| **c != 0.0).map(|(s, c)| (*s, *c)).collect(),
                None => vec![(sources[i], 1.0)],
            };
            fields.push(SendField { ty, terms, scale: scale[i], offset: offset[i] });
        }
    }
    let size = fields.iter().map(|f| f.ty.size()).sum();
    if packet.every_ticks == 0 {
        return Err(LayoutError(format!("packet `{}`: every_ticks must be at least 1", packet.name)));
    }
    Ok(BoundSend { name: packet.name.clone(), port: packet.port, every_ticks: packet.every_ticks, fields, size })
}

fn bind_receive(names: &SignalNames, packet: &PacketLayout) -> Result<BoundReceive, LayoutError> {
    let mut groups = Vec::new();
    for (k, field) in packet.fields.iter().enumerate() {
        let ty = scalar_type(packet, k, field)?;
        if field.from.is_some() || field.value.is_some() {
            return Err(LayoutError(format!("{}: `from` and `value` are for packets to the device", at(packet, k))));
        }
        let targets: Vec<Option<usize>> = match (&field.to, field.skip) {
            (Some(to), false) if field.count.is_none() => to
                .values()
                .iter()
                .map(|name| {
                    names.inputs.iter().position(|s| s == name).map(Some).ok_or_else(|| {
                        LayoutError(format!(
                            "{}: the plant has no input `{name}`; its inputs are: {}",
                            at(packet, k),
                            listed(names.inputs)
                        ))
                    })
                })
                .collect::<Result<_, _>>()?,
            (None, true) => vec![None; field.count.unwrap_or(1)],
            _ => {
                return Err(LayoutError(format!(
                    "{}: give either `to` (the plant inputs it carries) or `skip = true` (with `count`)",
                    at(packet, k)
                )));
            }
        };
        let n = targets.len();
        check_frame(packet, k, field, n)?;
        let scale = per_field(packet, k, "scale", &field.scale, n, 1.0)?;
        let offset = per_field(packet, k, "offset", &field.offset, n, 0.0)?;
        // Every frame map is orthogonal: its inverse is its transpose.
        let inverse_frame = field.frame.map(|f| {
            let m = f.matrix();
            (0..n).map(|i| (0..n).map(|j| m[j][i]).collect()).collect()
        });
        let fields = (0..n).map(|i| (ty, scale[i], offset[i])).collect();
        groups.push(ReceiveGroup { fields, inverse_frame, targets });
    }
    let size = groups.iter().flat_map(|g| &g.fields).map(|(ty, _, _)| ty.size()).sum();
    Ok(BoundReceive { name: packet.name.clone(), port: packet.port, groups, size })
}

impl DeviceLayout {
    /// Every field's type known, checked before the plant is (an unknown type named with its packet and field).
    pub fn check_types(&self) -> Result<(), LayoutError> {
        for packet in self.to_device.iter().chain(&self.from_device) {
            for (k, field) in packet.fields.iter().enumerate() {
                scalar_type(packet, k, field)?;
            }
        }
        Ok(())
    }

    /// Binds the layout to a plant's signals and the scenario's set points; every problem is named.
    pub fn bind(&self, names: &SignalNames) -> Result<BoundLayout, LayoutError> {
        let mut ports = BTreeSet::new();
        for packet in self.to_device.iter().chain(&self.from_device) {
            if packet.port == 0 {
                return Err(LayoutError(format!("packet `{}`: port 0 is not a port; give the UDP port", packet.name)));
            }
            if packet.fields.is_empty() {
                return Err(LayoutError(format!("packet `{}` has no fields", packet.name)));
            }
        }
        for packet in &self.from_device {
            if !ports.insert(packet.port) {
                return Err(LayoutError(format!(
                    "packet `{}`: the rig already listens on port {} for another packet; packets from the device \
                     need a port each",
                    packet.name, packet.port
                )));
            }
        }
        if self.to_device.is_empty() || self.from_device.is_empty() {
            return Err(LayoutError(format!(
                "device `{}` needs at least one packet each way ([[to_device]] and [[from_device]])",
                self.name
            )));
        }
        Ok(BoundLayout {
            name: self.name.clone(),
            byte_order: self.byte_order,
            to_device: self.to_device.iter().map(|p| bind_send(names, p)).collect::<Result<_, _>>()?,
            from_device: self.from_device.iter().map(|p| bind_receive(names, p)).collect::<Result<_, _>>()?,
        })
    }
}
