//! Wire samples as JSON, what the first recordings held (the logger now writes CDR, [`super::cdr`]); replay still
//! reads them. Built from each type's field table ([`silrig_wire::wire::WireField`]), like the CDR codec, whose field
//! shapes ([`shape`]) are these. Every field is written as received:
//! numbers with the shortest text that reads back to the same bits (non-finite values as `null`), integers exactly,
//! `SampleHeader` as a nested object, byte arrays (names and units) as strings. `_pad` fields are left out.
//! [`sample_from_json`] is the inverse, which replay uses to send the recorded samples again bit for bit.

use serde_json::Value;
use silrig_wire::wire::{SampleHeader, WireField, WireType};
use std::fmt::Write as _;

/// The element type of a field, from its Rust type as written in the wire definition (shared with [`super::cdr`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Element {
    F64,
    U64,
    I64,
    U32,
    Header,
    /// `[u8; N]`: NUL-padded text.
    Text,
}

impl Element {
    pub(super) fn size(self, text_len: usize) -> usize {
        match self {
            Element::F64 | Element::U64 | Element::I64 => 8,
            Element::U32 => 4,
            Element::Header => size_of::<SampleHeader>(),
            Element::Text => text_len,
        }
    }
}

/// A field's shape: its element, whether it is an array, and for text the bytes per string.
#[derive(Debug, Clone, Copy)]
pub(super) struct Shape {
    pub(super) element: Element,
    pub(super) array: bool,
    pub(super) text_len: usize,
}

fn element_of(rust_type: &str) -> Option<(Element, usize)> {
    match rust_type.trim() {
        "f64" => Some((Element::F64, 0)),
        "u64" => Some((Element::U64, 0)),
        "i64" => Some((Element::I64, 0)),
        "u32" => Some((Element::U32, 0)),
        "SampleHeader" => Some((Element::Header, 0)),
        t if t.starts_with("[u8;") => Some((Element::Text, 0)),
        _ => None,
    }
}

/// The shape of `field`; a type this codec does not know is a bug in the wire definition, caught by the tests that
/// encode every wire type.
pub(super) fn shape(field: &WireField) -> Shape {
    let t = field.rust_type.trim();
    if let Some((element, _)) = element_of(t) {
        let text_len = if element == Element::Text { field.size } else { 0 };
        return Shape { element, array: false, text_len };
    }
    // `[T; N]`: the element is what comes before the last `;`.
    let inner = t.strip_prefix('[').and_then(|s| s.rsplit_once(';')).map(|(e, _)| e.trim());
    match inner.and_then(element_of) {
        Some((Element::Text, _)) => {
            let inner = inner.expect("matched");
            let per = inner.trim_start_matches('[').rsplit_once(';').map(|(_, n)| n.trim().trim_end_matches(']'));
            // `[[u8; NAME_BYTES]; MAX_DIAGNOSTICS]`: the string length is the constant's value.
            let text_len = match per {
                Some("NAME_BYTES") => silrig_wire::wire::NAME_BYTES,
                Some("UNIT_BYTES") => silrig_wire::wire::UNIT_BYTES,
                Some(n) => n.parse().unwrap_or_else(|_| panic!("wire field {}: unknown length {n}", field.name)),
                None => panic!("wire field {}: cannot read type {t}", field.name),
            };
            Shape { element: Element::Text, array: true, text_len }
        }
        Some((element, _)) => Shape { element, array: true, text_len: 0 },
        None => panic!("wire field {}: no JSON form for type {t}", field.name),
    }
}

pub(super) fn fields_shown(fields: &'static [WireField]) -> impl Iterator<Item = &'static WireField> {
    fields.iter().filter(|f| !f.name.starts_with('_'))
}

fn read_u64(bytes: &[u8]) -> u64 {
    u64::from_ne_bytes(bytes[..8].try_into().expect("8 bytes"))
}

/// Append the JSON number for `v`: the shortest decimal that parses back to the same f64 (serde_json's formatter,
/// several times faster than `{:?}`, which matters at lockstep rates); NaN and infinities have no JSON form and are
/// written `null`.
pub fn push_f64(out: &mut String, v: f64) {
    // SAFETY: serde_json writes a JSON number (or `null` for a non-finite value), all ASCII, so the String stays
    // UTF-8.
    let bytes = unsafe { out.as_mut_vec() };
    serde_json::to_writer(bytes, &v).expect("writing to a Vec cannot fail");
}

fn push_element(out: &mut String, element: Element, bytes: &[u8]) {
    match element {
        Element::F64 => push_f64(out, f64::from_ne_bytes(bytes[..8].try_into().expect("8 bytes"))),
        Element::U64 => {
            let _ = write!(out, "{}", read_u64(bytes));
        }
        Element::I64 => {
            let _ = write!(out, "{}", i64::from_ne_bytes(bytes[..8].try_into().expect("8 bytes")));
        }
        Element::U32 => {
            let _ = write!(out, "{}", u32::from_ne_bytes(bytes[..4].try_into().expect("4 bytes")));
        }
        Element::Header => push_object(out, SampleHeader::FIELDS, bytes, &[]),
        Element::Text => {
            let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
            let text = String::from_utf8_lossy(&bytes[..end]);
            out.push_str(&Value::String(text.into_owned()).to_string());
        }
    }
}

fn push_object(out: &mut String, fields: &'static [WireField], bytes: &[u8], extra: &[(&str, u64)]) {
    out.push('{');
    let mut first = true;
    for field in fields_shown(fields) {
        if !first {
            out.push(',');
        }
        first = false;
        let _ = write!(out, "\"{}\":", field.name);
        let s = shape(field);
        let data = &bytes[field.offset..field.offset + field.size];
        if s.array {
            let step = s.element.size(s.text_len);
            out.push('[');
            for (i, chunk) in data.chunks_exact(step).enumerate() {
                if i > 0 {
                    out.push(',');
                }
                push_element(out, s.element, chunk);
            }
            out.push(']');
        } else {
            push_element(out, s.element, data);
        }
    }
    for (name, value) in extra {
        let _ = write!(out, ",\"{name}\":{value}");
    }
    out.push('}');
}

/// The bytes of a wire sample. Wire types are `#[repr(C)]` with explicit padding fields (their sizes are asserted
/// in `wire`), so every byte is a field's.
pub(super) fn bytes_of<T: WireType + Copy>(sample: &T) -> &[u8] {
    // SAFETY: T is a plain-old-data wire type (numbers and arrays of numbers, no implicit padding); reading its
    // bytes for its size is sound.
    unsafe { std::slice::from_raw_parts((sample as *const T).cast::<u8>(), size_of::<T>()) }
}

/// `sample` as a JSON object, every field but padding, then `extra` integer fields (the logger's receive stamp).
pub fn sample_json<T: WireType + Copy>(sample: &T, extra: &[(&str, u64)]) -> String {
    let mut out = String::with_capacity(64 * T::FIELDS.len());
    push_object(&mut out, T::FIELDS, bytes_of(sample), extra);
    out
}

/// A recorded field that does not fit the wire type.
#[derive(Debug, thiserror::Error)]
#[error("{type_name}: field `{field}`: {why}")]
pub struct JsonFieldError {
    type_name: &'static str,
    field: String,
    why: String,
}

fn put_element(
    type_name: &'static str,
    name: &str,
    element: Element,
    value: &Value,
    out: &mut [u8],
) -> Result<(), JsonFieldError> {
    let err = |why: String| JsonFieldError { type_name, field: name.to_string(), why };
    match element {
        Element::F64 => {
            let v = match value {
                Value::Null => f64::NAN,
                v => v.as_f64().ok_or_else(|| err(format!("expected a number, found {v}")))?,
            };
            out[..8].copy_from_slice(&v.to_ne_bytes());
        }
        Element::U64 => {
            let v = value.as_u64().ok_or_else(|| err(format!("expected an unsigned integer, found {value}")))?;
            out[..8].copy_from_slice(&v.to_ne_bytes());
        }
        Element::I64 => {
            let v = value.as_i64().ok_or_else(|| err(format!("expected an integer, found {value}")))?;
            out[..8].copy_from_slice(&v.to_ne_bytes());
        }
        Element::U32 => {
            let v = value
                .as_u64()
                .and_then(|v| u32::try_from(v).ok())
                .ok_or_else(|| err(format!("expected a 32-bit unsigned integer, found {value}")))?;
            out[..4].copy_from_slice(&v.to_ne_bytes());
        }
        Element::Header => put_object(SampleHeader::TYPE_NAME, SampleHeader::FIELDS, value, out)?,
        Element::Text => {
            let text = value.as_str().ok_or_else(|| err(format!("expected a string, found {value}")))?;
            if text.len() > out.len() {
                return Err(err(format!("{} bytes, at most {}", text.len(), out.len())));
            }
            out.fill(0);
            out[..text.len()].copy_from_slice(text.as_bytes());
        }
    }
    Ok(())
}

fn put_object(
    type_name: &'static str,
    fields: &'static [WireField],
    value: &Value,
    bytes: &mut [u8],
) -> Result<(), JsonFieldError> {
    let object = value.as_object().ok_or_else(|| JsonFieldError {
        type_name,
        field: String::new(),
        why: format!("expected an object, found {value}"),
    })?;
    for field in fields_shown(fields) {
        let missing = || JsonFieldError { type_name, field: field.name.into(), why: "missing".into() };
        let v = object.get(field.name).ok_or_else(missing)?;
        let s = shape(field);
        let data = &mut bytes[field.offset..field.offset + field.size];
        if s.array {
            let step = s.element.size(s.text_len);
            let items = v.as_array().filter(|a| a.len() * step == field.size).ok_or_else(|| JsonFieldError {
                type_name,
                field: field.name.into(),
                why: format!("expected an array of {} values", field.size / step),
            })?;
            for (chunk, item) in data.chunks_exact_mut(step).zip(items) {
                put_element(type_name, field.name, s.element, item, chunk)?;
            }
        } else {
            put_element(type_name, field.name, s.element, v, data)?;
        }
    }
    Ok(())
}

/// The sample a [`sample_json`] object holds, bit for bit (padding 0; a `null` number is NaN).
pub fn sample_from_json<T: WireType + Copy>(value: &Value) -> Result<T, JsonFieldError> {
    // SAFETY: every wire type is numbers and arrays of numbers, for which all-zero bytes are a valid value.
    let mut sample: T = unsafe { std::mem::zeroed() };
    // SAFETY: as in `bytes_of`; the slice covers exactly the sample, which outlives it, and any bytes are valid.
    let bytes = unsafe { std::slice::from_raw_parts_mut((&mut sample as *mut T).cast::<u8>(), size_of::<T>()) };
    put_object(T::TYPE_NAME, T::FIELDS, value, bytes)?;
    Ok(sample)
}

#[cfg(test)]
mod tests {
    use super::*;
    use silrig_wire::wire::{CommandSample, ControllerInfo, PlantSample};

    fn plant() -> PlantSample {
        let mut s = PlantSample::zeroed();
        s.header = SampleHeader { seq: 7, tick: 41, t_send_ns: u64::MAX - 3, epoch: 2, layout_version: 3, _pad: 0 };
        s.outputs = std::array::from_fn(|i| 0.1 * i as f64 + 1.0 / 3.0);
        s.outputs[4] = -0.0;
        s.outputs[5..8].copy_from_slice(&[-1e-300, 25.0, f64::MIN_POSITIVE]);
        s.outputs_len = 20;
        s.t_sim_s = 0.41;
        s.flags = 0b101;
        s.wake_lateness_ns = -12;
        s.previous_step_exec_ns = 4321;
        s
    }

    #[test]
    fn a_plant_sample_reads_back_bit_for_bit() {
        let s = plant();
        let text = sample_json(&s, &[("t_recv_ns", 99)]);
        let value: Value = serde_json::from_str(&text).expect("valid JSON");
        assert_eq!(value["header"]["tick"], 41);
        assert_eq!(value["header"]["t_send_ns"], u64::MAX - 3);
        assert_eq!(value["t_recv_ns"], 99);
        assert!(value.get("_pad").is_none());
        let back: PlantSample = sample_from_json(&value).expect("fits");
        assert_eq!(bytes_of(&back), bytes_of(&s));
    }

    #[test]
    fn non_finite_numbers_are_null_and_read_back_as_nan() {
        let mut c = CommandSample::zeroed();
        c.inputs_len = 3;
        c.inputs[..3].copy_from_slice(&[f64::NAN, f64::INFINITY, 1.5]);
        c.diagnostics_len = 2;
        c.diagnostics[1] = -2.25;
        let value: Value = serde_json::from_str(&sample_json(&c, &[])).expect("valid JSON");
        assert_eq!(
            value["inputs"].as_array().unwrap()[..3],
            serde_json::json!([null, null, 1.5]).as_array().unwrap()[..]
        );
        assert_eq!(value["diagnostics"].as_array().map(Vec::len), Some(silrig_wire::wire::MAX_DIAGNOSTICS));
        let back: CommandSample = sample_from_json(&value).expect("fits");
        assert!(back.inputs[0].is_nan() && back.inputs[1].is_nan() && back.inputs[2] == 1.5);
        assert_eq!(back.diagnostics[1], -2.25);
    }

    #[test]
    fn diagnostic_names_are_strings() {
        let info = ControllerInfo::new(&["s_phi".to_string(), "w_phi_0".to_string()]).expect("valid names");
        let value: Value = serde_json::from_str(&sample_json(&info, &[])).expect("valid JSON");
        assert_eq!(value["diagnostic_names"][1], "w_phi_0");
        assert_eq!(value["diagnostic_names"][2], "");
        let back: ControllerInfo = sample_from_json(&value).expect("fits");
        assert_eq!(back.names(), info.names());
    }

    #[test]
    fn a_field_of_the_wrong_kind_is_named() {
        let mut value: Value = serde_json::from_str(&sample_json(&plant(), &[])).expect("valid JSON");
        value["outputs"][2] = Value::String("x".into());
        let err = sample_from_json::<PlantSample>(&value).expect_err("refused").to_string();
        assert!(err.contains("`outputs`") && err.contains("expected a number"), "{err}");
        value.as_object_mut().expect("object").remove("flags");
        let err = sample_from_json::<PlantSample>(&value).expect_err("refused").to_string();
        assert!(err.contains("`flags`"), "{err}");
    }
}
