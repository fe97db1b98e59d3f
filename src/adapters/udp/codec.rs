//! A bound layout run each tick: a packet to the device written from the plant's outputs, the set points and the
//! time; a packet from the device read into the plant's inputs, refused whole when it has the wrong size or a
//! value that is not a finite number (so the rig holds the last good command, as it does for any controller).

use super::layout::{BoundReceive, BoundSend, ByteOrder, ScalarType, Source};

/// What a packet to the device is written from.
#[derive(Debug, Clone, Copy)]
pub struct SendValues<'a> {
    /// Simulated time, s.
    pub t_s: f64,
    /// The plant's outputs, announced order.
    pub outputs: &'a [f64],
    /// The set points, in the order the layout was bound against.
    pub setpoints: &'a [f64],
}

/// Why a packet from the device was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DecodeError {
    /// Not the layout's size.
    #[error("packet `{packet}` of {got} bytes refused: its layout has {want}")]
    WrongSize {
        /// The packet's name.
        packet: String,
        /// Bytes received.
        got: usize,
        /// Bytes the layout declares.
        want: usize,
    },
    /// A value that is not a finite number after scale and offset.
    #[error("packet `{packet}` refused: field {field} is {value}, not a finite number")]
    NotFinite {
        /// The packet's name.
        packet: String,
        /// 1-based field number.
        field: usize,
        /// The value.
        value: f64,
    },
}

fn put(out: &mut Vec<u8>, ty: ScalarType, order: ByteOrder, value: f64) {
    macro_rules! bytes {
        ($v:expr) => {
            match order {
                ByteOrder::Little => out.extend_from_slice(&$v.to_le_bytes()),
                ByteOrder::Big => out.extend_from_slice(&$v.to_be_bytes()),
            }
        };
    }
    // `as` from f64 to an integer saturates at the type's range and maps NaN to 0: what a device would be sent
    // for a value beyond its field.
    let r = value.round();
    match ty {
        ScalarType::U8 => bytes!(r as u8),
        ScalarType::I8 => bytes!(r as i8),
        ScalarType::U16 => bytes!(r as u16),
        ScalarType::I16 => bytes!(r as i16),
        ScalarType::U32 => bytes!(r as u32),
        ScalarType::I32 => bytes!(r as i32),
        ScalarType::U64 => bytes!(r as u64),
        ScalarType::I64 => bytes!(r as i64),
        ScalarType::F32 => bytes!(value as f32),
        ScalarType::F64 => bytes!(value),
    }
}

fn get(bytes: &[u8], ty: ScalarType, order: ByteOrder) -> f64 {
    macro_rules! read {
        ($t:ty) => {{
            let raw: [u8; std::mem::size_of::<$t>()] = bytes.try_into().expect("sized by the layout");
            match order {
                ByteOrder::Little => <$t>::from_le_bytes(raw) as f64,
                ByteOrder::Big => <$t>::from_be_bytes(raw) as f64,
            }
        }};
    }
    match ty {
        ScalarType::U8 => read!(u8),
        ScalarType::I8 => read!(i8),
        ScalarType::U16 => read!(u16),
        ScalarType::I16 => read!(i16),
        ScalarType::U32 => read!(u32),
        ScalarType::I32 => read!(i32),
        ScalarType::U64 => read!(u64),
        ScalarType::I64 => read!(i64),
        ScalarType::F32 => read!(f32),
        ScalarType::F64 => read!(f64),
    }
}

impl BoundSend {
    /// Writes this tick's packet into `out` (cleared first).
    pub fn encode(&self, order: ByteOrder, values: &SendValues, out: &mut Vec<u8>) {
        out.clear();
        for field in &self.fields {
            let raw: f64 = field
                .terms
                .iter()
                .map(|(source, coefficient)| {
                    coefficient
                        * match *source {
                            Source::Output(k) => values.outputs[k],
                            Source::Setpoint(k) => values.setpoints[k],
                            Source::Time => values.t_s,
                            Source::Constant(c) => c,
                        }
                })
                .sum();
            put(out, field.ty, order, raw * field.scale + field.offset);
        }
    }

    /// Whether it goes out at this tick.
    pub fn due(&self, tick: u64) -> bool {
        tick.is_multiple_of(u64::from(self.every_ticks))
    }
}

impl BoundReceive {
    /// Reads a packet into `inputs` (announced order); a refused packet changes nothing.
    pub fn decode(&self, order: ByteOrder, bytes: &[u8], inputs: &mut [f64]) -> Result<(), DecodeError> {
        if bytes.len() != self.size {
            return Err(DecodeError::WrongSize { packet: self.name.clone(), got: bytes.len(), want: self.size });
        }
        let mut updates = Vec::new();
        let (mut at, mut field) = (0, 0);
        for group in &self.groups {
            let mut decoded = Vec::with_capacity(group.fields.len());
            for (ty, scale, offset) in &group.fields {
                let value = get(&bytes[at..at + ty.size()], *ty, order) * scale + offset;
                at += ty.size();
                field += 1;
                let skipped = group.targets[decoded.len()].is_none();
                if !value.is_finite() && !skipped {
                    return Err(DecodeError::NotFinite { packet: self.name.clone(), field, value });
                }
                decoded.push(value);
            }
            let values = match &group.inverse_frame {
                Some(m) => m.iter().map(|row| row.iter().zip(&decoded).map(|(a, b)| a * b).sum()).collect(),
                None => decoded,
            };
            updates.extend(group.targets.iter().zip(values).filter_map(|(t, v)| t.map(|t| (t, v))));
        }
        for (target, value) in updates {
            inputs[target] = value;
        }
        Ok(())
    }
}
