//! The wire contract, generated from the Rust definitions so it can never drift from them: what a peer of the rig
//! written in another language must match (the sample layouts with every field's offset, size, type and unit, the
//! layout version, the header rules, the streams with their service names, type names, settings and event ids).
//! Three renderings: text for people (`silrig contract`), a C header with `_Static_assert`s on every offset and
//! size (`--c-header`), and a Python `ctypes` module (`--python`); each carries every rule a raw peer must keep.
//! Offsets come from `core::mem::offset_of!` on the types themselves ([`silrig_wire::wire::WireType::FIELDS`]).
//! It also owns the set of headers a C peer includes (`--c-dir`): the generated one and the client library's.

use silrig_rig::ProcessArgs;
use silrig_rig::session::Status;
use silrig_wire::ipc::StreamEvent;
use silrig_wire::topology::{STREAM_SETTINGS, Stream};
use silrig_wire::wire::{self, WIRE_LAYOUT_VERSION, WireField, WireType};
use std::fmt::Write as _;

/// One wire type as the contract lists it.
#[derive(Debug, Clone, Copy)]
pub struct ContractType {
    /// Rust name (`PlantSample`).
    pub name: &'static str,
    /// iceoryx2 type name.
    pub type_name: &'static str,
    /// Size in bytes.
    pub size: usize,
    /// Alignment in bytes.
    pub align: usize,
    /// Fields in memory order.
    pub fields: &'static [WireField],
    /// The type's doc line.
    pub doc: &'static str,
}

fn entry<T: WireType>(doc: &'static str) -> ContractType {
    ContractType {
        name: T::NAME,
        type_name: T::TYPE_NAME,
        size: size_of::<T>(),
        align: align_of::<T>(),
        fields: T::FIELDS,
        doc,
    }
}

/// Every wire type, the header first (the others embed it).
pub fn types() -> [ContractType; 6] {
    [
        entry::<wire::SampleHeader>("Bookkeeping that precedes every sample."),
        entry::<wire::PlantSample>("What the plant publishes every tick (stream `plant`)."),
        entry::<wire::CommandSample>("What the controller publishes in answer to a plant sample (stream `command`)."),
        entry::<wire::LogAckSample>("Rows the logger has written (stream `log-ack`, lockstep flow control)."),
        entry::<wire::ControllerInfo>(
            "The names of a controller's diagnostics, announced once per epoch before its first command (stream \
             `controller-info`).",
        ),
        entry::<wire::PlantInfo>(
            "The plant's name and signals, announced once per epoch before its first sample (stream `plant-info`).",
        ),
    ]
}

/// Constants a peer needs: (name, value, meaning).
fn constants() -> Vec<(&'static str, u64, &'static str)> {
    vec![
        ("WIRE_LAYOUT_VERSION", u64::from(WIRE_LAYOUT_VERSION), "layout version; every header carries it"),
        ("FLAG_COMMAND_STALE", u64::from(wire::FLAG_COMMAND_STALE), "the applied command is older than allowed"),
        ("FLAG_SATURATED", u64::from(wire::FLAG_SATURATED), "an input's actuator is at its position limit"),
        ("FLAG_FAILSAFE", u64::from(wire::FLAG_FAILSAFE), "the failsafe output is active"),
        ("FLAG_RATE_LIMITED", u64::from(wire::FLAG_RATE_LIMITED), "an actuator moved at its rate limit this tick"),
        ("FLAG_COMMAND_REFUSED", u64::from(wire::FLAG_COMMAND_REFUSED), "command refused (NaN/out of range): hold"),
        ("FLAG_END_OF_RUN", u64::from(wire::FLAG_END_OF_RUN), "the plant's last sample: last tick, its positions"),
        ("FLAG_OUTPUTS_HELD", u64::from(wire::FLAG_OUTPUTS_HELD), "outputs refused (NaN/inf): the last valid held"),
        ("MAX_OUTPUTS", wire::MAX_OUTPUTS as u64, "outputs a plant sample carries at most"),
        ("MAX_INPUTS", wire::MAX_INPUTS as u64, "inputs a command sample carries at most"),
        ("MAX_DIAGNOSTICS", wire::MAX_DIAGNOSTICS as u64, "diagnostics a command sample carries at most"),
        ("NAME_BYTES", wire::NAME_BYTES as u64, "bytes of a plant, signal or diagnostic name, NUL-padded"),
        ("UNIT_BYTES", wire::UNIT_BYTES as u64, "bytes of a unit, NUL-padded"),
        ("OUTPUT_IN_TRACE", u64::from(wire::OUTPUT_IN_TRACE), "PlantInfo.output_flags: a trace.csv column"),
        ("INPUT_COMMAND_IN_TRACE", u64::from(wire::INPUT_COMMAND_IN_TRACE), "PlantInfo.input_flags: command traced"),
        ("NO_OUTPUT", u64::from(wire::NO_OUTPUT), "PlantInfo.input_held_output: no position reported"),
        ("EVENT_SAMPLE_SENT", StreamEvent::SampleSent.id() as u64, "event id to notify after every send"),
        ("EVENT_FINISHED", StreamEvent::Finished.id() as u64, "event id: the plant has published its last tick"),
        ("EVENT_PUBLISHER_DEAD", StreamEvent::PublisherDead.id() as u64, "event id of a cleaned-up dead publisher"),
    ]
}

/// The rules of the sample header, for people (every rendering carries them as comments).
pub const HEADER_RULES: [&str; 9] = [
    "seq: starts at 0 for each publisher epoch and grows by 1 per sample sent; a jump means samples were lost",
    "tick: the plant tick the sample belongs to; a command carries the tick it answers (= answers_tick)",
    "t_send_ns: CLOCK_MONOTONIC at publish, ns (the one clock shared by every process of the machine)",
    "epoch: non-zero, a new value whenever the publishing process (re)starts",
    "layout_version: WIRE_LAYOUT_VERSION; a peer of another version is refused by its type names already",
    "_pad and every other padding field: 0",
    "after each send, notify the stream's event service with EVENT_SAMPLE_SENT; never send NaN or infinity",
    "a plant sample carries every output the plant announced (outputs_len = PlantInfo.outputs_len), in its order",
    "a command carries one value per input the plant announced (inputs_len = PlantInfo.inputs_len), in its order, \
     each within the input's min..max, or it is refused",
];

/// What each peer must do besides sending well-formed samples, for people (the text rendering carries it).
pub const PEER_RULES: [&str; 7] = [
    "a plant announces PlantInfo, then publishes one PlantSample per tick (0, 1, ...) once a command publisher exists; \
     after its last tick it sends that tick again with FLAG_END_OF_RUN, notifies EVENT_FINISHED on stream plant and \
     exits with status 0 (a --plant-cmd plant without a report: that exit is the end of its flight)",
    "a controller opens plant, plant-info, controller-info and command; it announces ControllerInfo (its diagnostics' \
     names, possibly none) before it creates its command publisher, which is what the plant starts on, and again with \
     its first command",
    "a controller takes its set points from the scenario the run flies (the TOML file SILRIG_SCENARIO names): its \
     [setpoint] table gives outputs by name in their unit, and phi_deg, theta_deg and psi_deg are 0 when not given; \
     its [[setpoint_steps]] change some of them during the run, each from its at_s on, so a sample is answered for \
     the set points in force at its t_sim_s (libsilrig_client reads them for you: silrig_session_setpoint_at)",
    "a command carries a value for every input, also those the controller does not command: for each, where its \
     actuator is in the sample being answered (the output PlantInfo.input_held_output names), or PlantInfo.input_hold \
     when it names none (NO_OUTPUT); libsilrig_client fills them in: silrig_session_held_command",
    "a controller answers each plant sample it takes with one CommandSample whose answers_tick and header tick are the \
     sample's tick; it need not answer every sample (a miss is held and counted by the plant), and never answers the \
     FLAG_END_OF_RUN sample",
    "a controller leaves when the run ends (the FLAG_END_OF_RUN sample, or EVENT_FINISHED on stream plant): it drops \
     its ports and its node; the launcher removes the run's shared memory once no node of the run is alive",
    "reports: the rig's processes and anything on libsilrig_client write <out>/<role>.report.json; a controller started \
     outside the launcher (--controller external) or a --plant-cmd plant that speaks the contract itself need not, \
     and the run's report then says whose measurements stand in for it",
];

/// How peers find each other's signals, for people (the text rendering carries it).
pub const SIGNAL_RULES: [&str; 4] = [
    "the plant announces PlantInfo on stream plant-info once per epoch, before its first sample; a reader that \
     joins later gets it from the stream's history (history 1: the plant calls update_connections every tick)",
    "names: ASCII letters, digits and '_', unique among the outputs and among the inputs; units: printable ASCII \
     without comma or quote",
    "a controller reads PlantInfo before answering a sample and finds the outputs it reads and the inputs it \
     commands by name, never by position; a restarted plant must announce the same signals",
    "trace.csv's columns: t_s, the traced outputs that are no input's position, the traced commands \
     (<input>_cmd_<unit>, or <input>_cmd when the unit is not a word), the traced positions, flight_segment, the \
     controller's diagnostics",
];

/// The rules every rendering carries, by section: (title, rules).
fn rule_sections() -> [(&'static str, &'static [&'static str]); 3] {
    [("Header rules", &HEADER_RULES), ("What each peer does", &PEER_RULES), ("Signals", &SIGNAL_RULES)]
}

/// The headers a C peer includes, by file name: the generated contract and `libsilrig_client.so`'s functions
/// (hand-written, it includes the contract by that name).
pub fn c_headers() -> [(&'static str, String); 2] {
    [("silrig_contract.h", c_header()), ("silrig_client.h", C_CLIENT_HEADER.to_string())]
}

/// `libsilrig_client.so`'s header, as checked in beside the examples (`silrig new` writes it too).
pub const C_CLIENT_HEADER: &str = include_str!("../../examples/c/silrig_client.h");

/// The contract as text for people.
pub fn text() -> String {
    let mut out = format!("silrig wire contract, layout version {WIRE_LAYOUT_VERSION}\n\nStreams (iceoryx2 0.10, ");
    out += "publish-subscribe and event services of the same name, in the run's namespace):\n";
    for s in Stream::ALL {
        let readers: Vec<String> = s.readers().iter().map(|(r, depth)| format!("{r} (queue {depth})")).collect();
        let _ = writeln!(
            out,
            "  {:<8} service \"{}\", payload {}, published by {}, read by {}; subscriber max buffer {}",
            s.label(),
            s.service_name(),
            s.payload_type_name(),
            s.publisher(),
            readers.join(", "),
            s.settings().subscriber_max_buffer
        );
    }
    let q = STREAM_SETTINGS;
    let _ = writeln!(
        out,
        "\nService settings every peer must ask for (iceoryx2 refuses others): safe overflow on, max publishers {}, \
         max subscribers {}, max nodes {}, subscriber max buffer the stream's own (above: its deepest reader's \
         queue), subscriber max borrowed samples {}, history {}; event service: max notifiers {}, max listeners {}, \
         notifier dead event {}.",
        q.max_publishers,
        q.max_subscribers,
        q.max_nodes,
        q.subscriber_max_borrowed,
        q.history_size,
        q.max_notifiers,
        q.max_subscribers,
        StreamEvent::PublisherDead.id()
    );
    out += "Namespace of run <id>: iceoryx2 root dir /dev/shm/silrig_<id>/, file prefix sr_<id>_.\n";
    for (title, rules) in rule_sections() {
        let _ = writeln!(out, "\n{title}:");
        for rule in rules {
            let _ = writeln!(out, "  - {rule}");
        }
    }
    out += "\nConstants:\n";
    for (name, value, meaning) in constants() {
        let _ = writeln!(out, "  {name:<22} {value:>10}  {meaning}");
    }
    out += "\nStatus codes of libsilrig_client.so (0 and above: no error; below 0: see silrig_last_error()):\n";
    for st in Status::ALL {
        let _ = writeln!(out, "  SILRIG_{:<22} {:>3}  {}", st.name(), st.code(), st.meaning());
    }
    out += "\nEnvironment of a controller or plant started by `silrig run --controller-cmd` or `--plant-cmd` (read by \
            silrig_session_open and silrig_plant_open):\n";
    for (name, help) in ProcessArgs::env_variables() {
        let _ = writeln!(out, "  {name:<28} {}", help.replace('\n', " "));
    }
    for t in types() {
        let _ = write!(out, "\n{} \"{}\": {} B, align {}. {}\n", t.name, t.type_name, t.size, t.align, t.doc);
        let _ = writeln!(out, "  {:>6} {:>5}  {:<24} {:<26} meaning", "offset", "size", "field", "type");
        for f in t.fields {
            let doc = f.doc.lines().map(str::trim).collect::<Vec<_>>().join(" ");
            let _ = writeln!(out, "  {:>6} {:>5}  {:<24} {:<26} {doc}", f.offset, f.size, f.name, f.rust_type);
        }
    }
    out
}

/// A Rust field type split into its element type and array lengths, outermost first (`[[u8; 32]; 4]` gives
/// (`u8`, [4, 32])). Lengths come from sizes, so `[f64; 3 * N]` needs no evaluation.
fn array_shape(rust_type: &str, size: usize) -> (&str, Vec<usize>) {
    let t = rust_type.trim();
    if let Some(inner) = t.strip_prefix('[').and_then(|x| x.strip_suffix(']')) {
        let elem = inner[..inner.rfind(';').expect("an array type has a length")].trim();
        let elem_size = type_size(elem);
        let (base, mut dims) = array_shape(elem, elem_size);
        dims.insert(0, size / elem_size);
        return (base, dims);
    }
    (t, Vec::new())
}

/// Size of a scalar, a wire type, or an array of them with a literal length or one of the contract's constants.
fn type_size(rust_type: &str) -> usize {
    let t = rust_type.trim();
    if let Some(inner) = t.strip_prefix('[').and_then(|x| x.strip_suffix(']')) {
        let (elem, len) = inner.rsplit_once(';').expect("an array type has a length");
        let len = len.trim();
        let len = len.parse().ok().or_else(|| constants().iter().find(|c| c.0 == len).map(|c| c.1 as usize));
        let len = len.expect("nested array lengths are literals or contract constants");
        return type_size(elem) * len;
    }
    match t {
        "u8" | "i8" => 1,
        "u16" | "i16" => 2,
        "u32" | "i32" | "f32" => 4,
        "u64" | "i64" | "f64" => 8,
        other => types().iter().find(|c| c.name == other).map(|c| c.size).expect("a known wire type"),
    }
}

fn c_struct_name(rust_name: &str) -> String {
    let mut snake = String::new();
    for (i, ch) in rust_name.chars().enumerate() {
        if ch.is_ascii_uppercase() && i > 0 {
            snake.push('_');
        }
        snake.push(ch.to_ascii_lowercase());
    }
    format!("silrig_{snake}_t")
}

/// Rust scalar types and their C and Python ctypes names.
const SCALARS: [(&str, &str, &str); 10] = [
    ("u8", "uint8_t", "ctypes.c_uint8"),
    ("i8", "int8_t", "ctypes.c_int8"),
    ("u16", "uint16_t", "ctypes.c_uint16"),
    ("i16", "int16_t", "ctypes.c_int16"),
    ("u32", "uint32_t", "ctypes.c_uint32"),
    ("i32", "int32_t", "ctypes.c_int32"),
    ("u64", "uint64_t", "ctypes.c_uint64"),
    ("i64", "int64_t", "ctypes.c_int64"),
    ("f32", "float", "ctypes.c_float"),
    ("f64", "double", "ctypes.c_double"),
];

fn c_scalar(t: &str) -> String {
    SCALARS.iter().find(|s| s.0 == t).map_or_else(|| c_struct_name(t), |s| s.1.to_string())
}

fn py_scalar(t: &str) -> String {
    SCALARS.iter().find(|s| s.0 == t).map_or_else(|| t.to_string(), |s| s.2.to_string())
}

fn comment_lines(doc: &str, indent: &str, lead: &str) -> String {
    doc.lines().map(|l| format!("{indent}{lead} {}\n", l.trim())).collect()
}

/// The contract as a C header (also valid C++): constants, one struct per wire type, and a static assertion on
/// every size and offset, so a compiler that lays a struct out otherwise refuses to build.
pub fn c_header() -> String {
    let mut out = format!(
        "/* silrig wire contract, layout version {WIRE_LAYOUT_VERSION}.\n * Generated by `silrig contract --c-header`: \
         do not edit; regenerate after a layout change. */\n#ifndef SILRIG_CONTRACT_H\n#define SILRIG_CONTRACT_H\n\n\
         #include <stddef.h>\n#include <stdint.h>\n\n#ifdef __cplusplus\n#define SILRIG_STATIC_ASSERT(c, m) \
         static_assert(c, m)\n#define SILRIG_ALIGNOF(t) alignof(t)\n#else\n#define SILRIG_STATIC_ASSERT(c, m) \
         _Static_assert(c, m)\n#define SILRIG_ALIGNOF(t) _Alignof(t)\n#endif\n\n"
    );
    for (title, rules) in rule_sections() {
        let _ = writeln!(out, "/* {title}:");
        for rule in rules {
            let _ = writeln!(out, " *  - {rule}");
        }
        out += " */\n";
    }
    out += "\n";
    for (name, value, meaning) in constants() {
        let _ = writeln!(out, "/* {meaning} */\n#define SILRIG_{name} {value}u");
    }
    out += "\n/* Status codes of libsilrig_client.so: 0 and above are not errors. */\n";
    for st in Status::ALL {
        let _ = writeln!(out, "#define SILRIG_{} ({}) /* {} */", st.name(), st.code(), st.meaning());
    }
    out += "\n";
    for s in Stream::ALL {
        let upper = s.label().to_uppercase().replace('-', "_");
        let _ = writeln!(out, "#define SILRIG_SERVICE_{upper} \"{}\"", s.service_name());
        let _ = writeln!(out, "#define SILRIG_TYPE_NAME_{upper} \"{}\"", s.payload_type_name());
        let _ = writeln!(out, "#define SILRIG_SUBSCRIBER_MAX_BUFFER_{upper} {}u", s.settings().subscriber_max_buffer);
    }
    for t in types() {
        let c_name = c_struct_name(t.name);
        let _ = write!(out, "\n/* {} iceoryx2 type name \"{}\". */\ntypedef struct {c_name} {{\n", t.doc, t.type_name);
        for f in t.fields {
            out += &comment_lines(f.doc, "    ", "//");
            let (base, dims) = array_shape(f.rust_type, f.size);
            let dims: String = dims.iter().map(|d| format!("[{d}]")).collect();
            let _ = writeln!(out, "    {} {}{dims};", c_scalar(base), f.name);
        }
        let _ = writeln!(out, "}} {c_name};");
        let _ = writeln!(out, "SILRIG_STATIC_ASSERT(sizeof({c_name}) == {}, \"size of {}\");", t.size, t.name);
        let _ = writeln!(
            out,
            "SILRIG_STATIC_ASSERT(SILRIG_ALIGNOF({c_name}) == {}, \"alignment of {}\");",
            t.align, t.name
        );
        for f in t.fields {
            let _ = writeln!(
                out,
                "SILRIG_STATIC_ASSERT(offsetof({c_name}, {}) == {}, \"offset of {}.{}\");",
                f.name, f.offset, t.name, f.name
            );
        }
    }
    out += "\n#endif /* SILRIG_CONTRACT_H */\n";
    out
}

/// The contract as a Python `ctypes` module, with the `type_name()` static methods iceoryx2's Python binding
/// asks payload types for, and checks of every size and offset when it is imported.
pub fn python_module() -> String {
    let mut out = format!(
        "\"\"\"silrig wire contract, layout version {WIRE_LAYOUT_VERSION}.\n\nGenerated by `silrig contract --python`: \
         do not edit; regenerate after a layout change.\n"
    );
    for (title, rules) in rule_sections() {
        let _ = writeln!(out, "\n{title}:");
        for rule in rules {
            let _ = writeln!(out, "  - {rule}");
        }
    }
    out += "\"\"\"\n\nimport ctypes\n\n";
    for (name, value, meaning) in constants() {
        let _ = writeln!(out, "{name} = {value}  # {meaning}");
    }
    out += "\n# Status codes of libsilrig_client.so: 0 and above are not errors.\n";
    for st in Status::ALL {
        let _ = writeln!(out, "{} = {}  # {}", st.name(), st.code(), st.meaning());
    }
    out += "\nSERVICES = {\n";
    for s in Stream::ALL {
        let _ = writeln!(out, "    \"{}\": \"{}\",", s.label(), s.service_name());
    }
    out += "}\n\n# The subscriber max buffer each stream's services are opened with (iceoryx2 refuses a peer asking \
            for more).\nSUBSCRIBER_MAX_BUFFER = {\n";
    for s in Stream::ALL {
        let _ = writeln!(out, "    \"{}\": {},", s.label(), s.settings().subscriber_max_buffer);
    }
    out += "}\n";
    for t in types() {
        let _ = write!(out, "\n\nclass {}(ctypes.Structure):\n    \"\"\"{}\"\"\"\n\n    _fields_ = [\n", t.name, t.doc);
        for f in t.fields {
            out += &comment_lines(f.doc, "        ", "#");
            let (base, dims) = array_shape(f.rust_type, f.size);
            let ty = dims.iter().rev().fold(py_scalar(base), |acc, d| format!("{acc} * {d}"));
            let _ = writeln!(out, "        (\"{}\", {ty}),", f.name);
        }
        let _ = write!(
            out,
            "    ]\n\n    @staticmethod\n    def type_name() -> str:\n        return \"{}\"\n\n\n\
             assert ctypes.sizeof({}) == {}, \"size of {}\"\n\
             assert ctypes.alignment({}) == {}, \"alignment of {}\"\n",
            t.type_name, t.name, t.size, t.name, t.name, t.align, t.name
        );
        for f in t.fields {
            let _ = writeln!(
                out,
                "assert {}.{}.offset == {}, \"offset of {}.{}\"",
                t.name, f.name, f.offset, t.name, f.name
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_shapes_come_from_sizes() {
        assert_eq!(array_shape("u64", 8), ("u64", vec![]));
        assert_eq!(array_shape("[f64; 13]", 104), ("f64", vec![13]));
        assert_eq!(array_shape("[f64; 3 * N]", 384), ("f64", vec![48]));
        assert_eq!(array_shape("[[u8; 32]; 4]", 128), ("u8", vec![4, 32]));
        assert_eq!(array_shape("[[u8; NAME_BYTES]; MAX_DIAGNOSTICS]", 2048), ("u8", vec![64, 32]));
        assert_eq!(c_struct_name("LogAckSample"), "silrig_log_ack_sample_t");
    }

    #[test]
    fn fields_tile_each_type_and_say_what_they_are() {
        for t in types() {
            let mut end = 0;
            for f in t.fields {
                assert!(f.offset >= end, "{}.{} overlaps", t.name, f.name);
                assert!(!f.doc.trim().is_empty(), "{}.{} has no doc", t.name, f.name);
                end = f.offset + f.size;
            }
            assert_eq!(end, t.size, "{} has trailing padding the contract does not name", t.name);
        }
    }
}
