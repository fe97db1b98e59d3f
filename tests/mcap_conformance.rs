//! Our MCAP writer (`src/recording/mcap_writer.rs`) held to the MCAP project's conformance suite for writers,
//! without the suite's files (which stay out of this repository): the suite's inputs (no data, one message, one
//! schemaless message, one metadata record, ten messages) are built here in its JSON form, in every combination of
//! the features our writer has (chunks, message and chunk indexes, statistics, schemas and channels repeated in
//! the summary, metadata indexes, summary offsets) under the suite's rules, read by the same code the suite's runner
//! program uses (`examples/mcap_conformance_writer`), and the bytes written must equal those of the `mcap` crate's
//! writer (one of the suite's reference writers) configured the same way. Every file is read back by the `mcap`
//! crate and by Foxglove's Python `mcap` reader. Beyond the suite: files of several chunks, uncompressed (bytes
//! equal again) and compressed with LZ4 and zstd (compressed differently from the crate, so compared as read back).
//! The variants the writer does not support (attachments, padded records) must be refused in words.

#[path = "../examples/mcap_conformance_writer/variant.rs"]
mod variant;

mod common;

use serde_json::{Value, json};
use silrig::recording::mcap_writer::{ChunkCompression, McapOptions};
use std::collections::BTreeMap;
use std::io::Cursor;
use variant::{Record, Refusal, Variant};

/// The features our writer has, in the suite's order of its feature list (without `ax` and `pad`).
const FEATURES: [&str; 8] = ["ch", "mx", "st", "rsh", "rch", "mdx", "chx", "sum"];

/// A record in the suite's JSON form: its fields as `[name, value]` pairs, numbers as decimal strings.
fn record(kind: &str, fields: &[(&str, Value)]) -> Value {
    json!({"type": kind, "fields": fields.iter().map(|(k, v)| json!([k, v])).collect::<Vec<_>>()})
}

fn bytes(b: &[u8]) -> Value {
    b.iter().map(|x| x.to_string()).collect()
}

fn message(sequence: u32, log_time_ns: u64, publish_time_ns: u64) -> Value {
    let n = |x: u64| json!(x.to_string());
    let fields = [
        ("channel_id", json!("1")),
        ("data", bytes(&[1, 2, 3])),
        ("log_time", n(log_time_ns)),
        ("publish_time", n(publish_time_ns)),
        ("sequence", n(u64::from(sequence))),
    ];
    record("Message", &fields)
}

fn schema() -> Value {
    let fields =
        [("data", bytes(&[4, 5, 6])), ("encoding", json!("c")), ("id", json!("1")), ("name", json!("Example"))];
    record("Schema", &fields)
}

fn channel(schema_id: &str, message_encoding: &str, metadata: Value) -> Value {
    let fields = [
        ("id", json!("1")),
        ("message_encoding", json!(message_encoding)),
        ("metadata", metadata),
        ("schema_id", json!(schema_id)),
        ("topic", json!("example")),
    ];
    record("Channel", &fields)
}

/// The suite's inputs: name and records.
fn inputs() -> Vec<(&'static str, Vec<Value>)> {
    // Ten messages, some out of log-time order, numbered from 0.
    let ten = [0, 2, 1, 3, 3, 5, 4, 7, 8, 9].into_iter().enumerate().map(|(k, t)| message(k as u32, t, t));
    vec![
        ("NoData", vec![]),
        ("OneSchemalessMessage", vec![channel("0", "text", json!({})), message(10, 2, 1)]),
        ("OneMessage", vec![schema(), channel("1", "a", json!({"foo": "bar"})), message(10, 2, 1)]),
        (
            "OneMetadata",
            vec![record("Metadata", &[("metadata", json!({"foo": "bar"})), ("name", json!("myMetadata"))])],
        ),
        ("TenMessages", [schema(), channel("1", "a", json!({"foo": "bar"}))].into_iter().chain(ten).collect()),
    ]
}

/// Whether the suite makes a variant of `records` with `features`: a feature needs the records it indexes or
/// repeats, indexes need chunks, and summary offsets need a summary group besides.
fn makes_sense(records: &[Value], features: &[&str]) -> bool {
    let has = |f: &str| features.contains(&f);
    let holds = |kinds: &[&str]| records.iter().any(|r| kinds.contains(&r["type"].as_str().unwrap()));
    !(has("mdx") && !holds(&["Metadata"])
        || has("rsh") && !holds(&["Schema"])
        || has("rch") && !holds(&["Channel"])
        || (has("ch") || has("chx") || has("mx")) && !holds(&["Message", "Channel", "Schema"])
        || has("sum") && !["chx", "rsh", "rch", "mdx", "st"].iter().any(|f| has(f))
        || (has("chx") || has("mx")) && !has("ch"))
}

/// Every variant: its suite name (`OneMessage-ch-mx`, features sorted) and its JSON.
fn variants() -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (base, records) in inputs() {
        for mask in 0..1u32 << FEATURES.len() {
            let mut features: Vec<&str> =
                (0..FEATURES.len()).filter(|k| mask >> k & 1 == 1).map(|k| FEATURES[k]).collect();
            if !makes_sense(&records, &features) {
                continue;
            }
            features.sort();
            let name = std::iter::once(base).chain(features.iter().copied()).collect::<Vec<_>>().join("-");
            let doc = json!({"records": records, "meta": {"variant": {"features": features}}});
            out.push((name, doc.to_string()));
        }
    }
    out
}

/// The file the `mcap` crate's writer writes for `v`, configured as the suite's Rust writer runner configures it.
fn reference(v: &Variant, compression: Option<mcap::Compression>) -> Vec<u8> {
    let has = |f: &str| v.features.iter().any(|g| g == f);
    let options = mcap::WriteOptions::new()
        .compression(compression)
        .profile("")
        .library("")
        .use_chunks(has("ch"))
        .emit_message_indexes(has("mx"))
        .emit_statistics(has("st"))
        .repeat_schemas(has("rsh"))
        .repeat_channels(has("rch"))
        .emit_metadata_indexes(has("mdx"))
        .emit_chunk_indexes(has("chx"))
        .emit_summary_offsets(has("sum"))
        .emit_attachment_indexes(false);
    let mut w = options.create(Cursor::new(Vec::new())).unwrap();
    let (mut schemas, mut channels) = (BTreeMap::from([(0, 0)]), BTreeMap::new());
    for r in &v.records {
        match r {
            Record::Schema { id, name, encoding, data } => {
                schemas.insert(*id, w.add_schema(name, encoding, data).unwrap());
            }
            Record::Channel { id, schema_id, topic, message_encoding, metadata } => {
                channels.insert(*id, w.add_channel(schemas[schema_id], topic, message_encoding, metadata).unwrap());
            }
            Record::Message { channel_id, sequence, log_time_ns, publish_time_ns, data } => {
                let header = mcap::records::MessageHeader {
                    channel_id: channels[channel_id],
                    sequence: *sequence,
                    log_time: *log_time_ns,
                    publish_time: *publish_time_ns,
                };
                w.write_to_known_channel(&header, data).unwrap();
            }
            Record::Metadata { name, metadata } => {
                w.write_metadata(&mcap::records::Metadata { name: name.clone(), metadata: metadata.clone() }).unwrap();
            }
        }
    }
    w.finish().unwrap();
    w.into_inner().into_inner()
}

/// Where two files first differ, in words.
fn first_difference(ours: &[u8], theirs: &[u8]) -> String {
    let at = ours.iter().zip(theirs).position(|(a, b)| a != b).unwrap_or(ours.len().min(theirs.len()));
    let around = |b: &[u8]| format!("{:02x?}", &b[at.saturating_sub(8)..(at + 8).min(b.len())]);
    format!(
        "{} bytes against {}, first difference at byte {at}: ours {} theirs {}",
        ours.len(),
        theirs.len(),
        around(ours),
        around(theirs)
    )
}

/// The messages of `v`: (topic, sequence, log time, publish time, data), in the order written.
fn messages_of(v: &Variant) -> Vec<(String, u32, u64, u64, Vec<u8>)> {
    let topic = |id: &u16| {
        v.records.iter().find_map(|r| match r {
            Record::Channel { id: c, topic, .. } if c == id => Some(topic.clone()),
            _ => None,
        })
    };
    let message = |r: &Record| match r {
        Record::Message { channel_id, sequence, log_time_ns, publish_time_ns, data } => {
            Some((topic(channel_id).unwrap(), *sequence, *log_time_ns, *publish_time_ns, data.clone()))
        }
        _ => None,
    };
    v.records.iter().filter_map(message).collect()
}

/// What the `mcap` crate reads of `file`: its messages in file order, checking every CRC, and its statistics record.
fn read_back(file: &[u8]) -> (Vec<(String, u32, u64, u64, Vec<u8>)>, Option<mcap::records::Statistics>) {
    let messages = mcap::MessageStream::new(file)
        .unwrap()
        .map(|m| {
            let m = m.unwrap();
            (m.channel.topic.clone(), m.sequence, m.log_time, m.publish_time, m.data.into_owned())
        })
        .collect();
    // Record by record: `mcap::Summary::read` refuses a summary that repeats channels but not their schemas, which
    // the suite's variants (and the crate's writer) make.
    let mut records = mcap::read::LinearReader::new(file).unwrap().map(|r| r.unwrap());
    let stats = records.find_map(|r| match r {
        mcap::records::Record::Statistics(s) => Some(s),
        _ => None,
    });
    (messages, stats)
}

#[test]
fn every_variant_of_the_suites_inputs_is_byte_for_byte_the_mcap_crates_file() {
    let variants = variants();
    // The suite at foxglove/mcap 95d0673 has 201 variants of these inputs without attachments or padding.
    assert_eq!(variants.len(), 201, "the variants built here no longer match the suite's rules");
    let dir = common::temp_dir("mcap_conformance", "every_variant");
    for (name, json) in &variants {
        let v = variant::parse(json).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        let ours = variant::write(&v).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        let theirs = reference(&v, None);
        assert!(ours == theirs, "{name}: {}", first_difference(&ours, &theirs));
        let (messages, stats) = read_back(&ours);
        assert_eq!(messages, messages_of(&v), "{name}");
        let has = |f: &str| v.features.iter().any(|g| g == f);
        assert_eq!(stats.map(|s| s.message_count), has("st").then_some(messages.len() as u64), "{name}");
        std::fs::write(dir.join(format!("{name}.mcap")), &ours).unwrap();
    }
    python_reads_every_file(&dir, &variants);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Foxglove's Python `mcap` reader reads each file's messages straight through (checking the CRCs) and, where the
/// summary has chunk indexes and the schemas of its channels, through the indexes as well (what Foxglove's indexed
/// reader does); and its statistics. All equal to the variant's.
fn python_reads_every_file(dir: &std::path::Path, variants: &[(String, String)]) {
    let python = common::venv_python("mcap", "mcap");
    const READ: &str = r#"
import json, os, sys
from mcap.reader import NonSeekingReader, SeekingReader
from mcap.stream_reader import StreamReader
from mcap.records import Statistics

def listed(messages):
    return [[c.topic, m.sequence, m.log_time, m.publish_time, list(m.data)] for _, c, m in messages]

out = {}
for name in sorted(os.listdir(sys.argv[1])):
    path = os.path.join(sys.argv[1], name)
    with open(path, "rb") as f:
        streamed = listed(NonSeekingReader(f, validate_crcs=True).iter_messages(log_time_order=False))
    with open(path, "rb") as f:
        stats = [r for r in StreamReader(f, skip_magic=False).records if isinstance(r, Statistics)]
    with open(path, "rb") as f:
        reader = SeekingReader(f, validate_crcs=True)
        summary = reader.get_summary()
        indexable = summary is not None and summary.chunk_indexes and summary.channels and all(
            c.schema_id == 0 or c.schema_id in summary.schemas for c in summary.channels.values())
        indexed = listed(reader.iter_messages(log_time_order=False)) if indexable else None
    out[name[:-5]] = {"streamed": streamed, "indexed": indexed, "count": stats[0].message_count if stats else None}
print(json.dumps(out))
"#;
    let out = std::process::Command::new(python).args(["-c", READ]).arg(dir).output().unwrap();
    assert!(out.status.success(), "python mcap reader: {}", String::from_utf8_lossy(&out.stderr));
    let read: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(read.as_object().unwrap().len(), variants.len());
    let mut indexed_reads = 0;
    for (name, json) in variants {
        let v = variant::parse(json).unwrap();
        let has = |f: &str| v.features.iter().any(|g| g == f);
        let expected: Vec<Value> = messages_of(&v).into_iter().map(|(t, s, l, p, d)| json!([t, s, l, p, d])).collect();
        assert_eq!(read[name]["streamed"].as_array(), Some(&expected), "{name}");
        // Chunk indexes and the channels (with their schemas, if any) in the summary: an indexed reader reads it.
        let schemaless = v.records.iter().all(|r| !matches!(r, Record::Schema { .. }));
        if has("chx") && has("rch") && (has("rsh") || schemaless) {
            indexed_reads += 1;
            // In index order, chunk by chunk: here one chunk, so in the order written.
            assert_eq!(read[name]["indexed"].as_array(), Some(&expected), "{name}: through the indexes");
        }
        assert_eq!(read[name]["count"].as_u64(), has("st").then_some(expected.len() as u64), "{name}");
    }
    // ch, chx and rch, with rsh or schemaless, and any of mx, st and sum: 8 variants each of the three inputs.
    assert_eq!(indexed_reads, 24, "variants read through their indexes");
}

/// Two channels, 2600 messages of 1 kB (more than two chunks of 1 MiB) with a metadata record among them.
fn several_chunks(features: &[&str]) -> Variant {
    let mut records = vec![Record::Schema { id: 1, name: "s".into(), encoding: "c".into(), data: vec![9; 40] }];
    for (id, schema_id) in [(1, 1), (2, 0)] {
        let (topic, metadata) = (format!("/t{id}"), BTreeMap::from([("k".to_string(), id.to_string())]));
        records.push(Record::Channel { id, schema_id, topic, message_encoding: "e".into(), metadata });
    }
    for k in 0..2600u64 {
        let data = (0..1000).map(|x| (x * 7 + k) as u8).collect();
        let channel_id = 1 + (k % 3 == 0) as u16;
        records.push(Record::Message {
            channel_id,
            sequence: k as u32,
            log_time_ns: 5000 - k,
            publish_time_ns: k,
            data,
        });
        if k == 1500 {
            records.push(Record::Metadata { name: "middle".into(), metadata: BTreeMap::new() });
        }
    }
    Variant { features: features.iter().map(|f| f.to_string()).collect(), records }
}

#[test]
fn files_of_several_chunks_are_the_mcap_crates_and_compressed_ones_read_back_the_same() {
    let all = ["ch", "mx", "st", "rsh", "rch", "mdx", "chx", "sum"];
    for features in [&all[..], &["ch", "mx", "st"], &["st", "mdx", "sum"]] {
        let v = several_chunks(features);
        let ours = variant::write(&v).unwrap();
        let theirs = reference(&v, None);
        assert!(ours == theirs, "{features:?}: {}", first_difference(&ours, &theirs));
        assert_eq!(read_back(&ours).0, messages_of(&v));
    }
    // Compressed: the same records, so the same messages, statistics, chunk bounds and uncompressed sizes.
    let v = several_chunks(&all);
    let options = variant::options(&v.features).unwrap();
    for (ours_compression, theirs_compression) in
        [(ChunkCompression::Lz4, mcap::Compression::Lz4), (ChunkCompression::Zstd(3), mcap::Compression::Zstd)]
    {
        let ours = variant::write_with(&v, McapOptions { compression: ours_compression, ..options }).unwrap();
        let theirs = reference(&v, Some(theirs_compression));
        assert_eq!(read_back(&ours), read_back(&theirs), "{ours_compression:?}");
        let chunks = |file: &[u8]| {
            let summary = mcap::Summary::read(file).unwrap().unwrap();
            let index = |c: &mcap::records::ChunkIndex| {
                (c.message_start_time, c.message_end_time, c.uncompressed_size, c.compression.clone())
            };
            summary.chunk_indexes.iter().map(index).collect::<Vec<_>>()
        };
        assert!(chunks(&ours).len() >= 3, "{} chunks", chunks(&ours).len());
        assert_eq!(chunks(&ours), chunks(&theirs), "{ours_compression:?}");
    }
}

#[test]
fn the_summary_in_a_variant_is_not_written_twice() {
    // The suite's files list the expected summary after the data section's end: a channel repeated there (and a
    // schema) is the summary's copy, not a second channel.
    let (_, json) = variants().into_iter().find(|(name, _)| name == "OneMessage-rch-rsh").unwrap();
    let mut doc: Value = serde_json::from_str(&json).unwrap();
    let records = doc["records"].as_array_mut().unwrap();
    let repeated = [records[1].clone(), records[0].clone()];
    records.push(record("DataEnd", &[("data_section_crc", json!("0"))]));
    records.extend(repeated);
    let v = variant::parse(&doc.to_string()).unwrap();
    assert_eq!(v, variant::parse(&json).unwrap());
    assert_eq!(v.records.len(), 3);
}

#[test]
fn what_the_writer_does_not_do_is_refused_in_words() {
    let attachment =
        json!({"records": [record("Attachment", &[("name", json!("f"))])], "meta": {"variant": {"features": []}}});
    let refusals = [
        (attachment.to_string(), "the writer writes no attachments"),
        (json!({"records": [], "meta": {"variant": {"features": ["ax"]}}}).to_string(), "writes no attachments"),
        (json!({"records": [], "meta": {"variant": {"features": ["pad"]}}}).to_string(), "only a reader test needs"),
    ];
    for (json, why) in refusals {
        match variant::parse(&json).and_then(|v| variant::write(&v)) {
            Err(Refusal::Unsupported(said)) => assert!(said.contains(why), "{said}"),
            other => panic!("{json}: {other:?}"),
        }
    }
    let invalid = [
        (r#"{"records": []}"#, "no meta.variant.features list"),
        (
            r#"{"records": [{"type": "Message", "fields": []}], "meta": {"variant": {"features": []}}}"#,
            "without `channel_id`",
        ),
        (r#"{"records": [], "meta": {"variant": {"features": ["zz"]}}}"#, "unknown feature `zz`"),
        (r#"{"records": [{"type": "Chunk"}], "meta": {"variant": {"features": []}}}"#, "unknown record type `Chunk`"),
    ];
    for (json, why) in invalid {
        match variant::parse(json).and_then(|v| variant::write(&v)) {
            Err(Refusal::Invalid(said)) => assert!(said.contains(why), "{said}"),
            other => panic!("{json}: {other:?}"),
        }
    }
    let message = json!({"records": [message(1, 1, 1)], "meta": {"variant": {"features": []}}}).to_string();
    match variant::parse(&message).and_then(|v| variant::write(&v)) {
        Err(Refusal::Invalid(said)) => assert!(said.contains("a channel id 1 no earlier record added"), "{said}"),
        other => panic!("{other:?}"),
    }
}
