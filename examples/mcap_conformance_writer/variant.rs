//! A writer variant of the MCAP project's conformance suite (`tests/conformance` of foxglove/mcap): the records to
//! write and the features the file must have, read from the suite's JSON form, and the file our MCAP writer
//! ([`silrig::recording::mcap_writer`]) writes for them. The suite holds a writer to its expected file byte for
//! byte. Shared by `examples/mcap_conformance_writer` (the suite's runner protocol: a variant's JSON in, the file on
//! stdout) and `tests/mcap_conformance.rs` (variants built like the suite's, against the `mcap` crate's writer).

use serde_json::Value;
use silrig::recording::mcap_writer::{ChunkCompression, McapOptions, McapWriter};
use std::collections::{BTreeMap, HashMap};

/// A record the writer is asked to write; the suite's other records (header, indexes, statistics, summary offsets,
/// footer) and every record after the data section's end (the summary, schemas and channels repeated) are what a
/// writer derives, so they are not inputs.
#[derive(Debug, Clone, PartialEq)]
pub enum Record {
    /// A schema, under the variant's id.
    Schema { id: u16, name: String, encoding: String, data: Vec<u8> },
    /// A channel, under the variant's id; schema 0: none.
    Channel { id: u16, schema_id: u16, topic: String, message_encoding: String, metadata: BTreeMap<String, String> },
    /// A message on a channel of the variant.
    Message { channel_id: u16, sequence: u32, log_time_ns: u64, publish_time_ns: u64, data: Vec<u8> },
    /// A metadata record.
    Metadata { name: String, metadata: BTreeMap<String, String> },
}

/// A variant: its records in order and its features (the suite's short names: `ch` chunks, `mx` message indexes,
/// `st` statistics, `rsh` and `rch` schemas and channels repeated in the summary, `mdx` metadata indexes, `chx`
/// chunk indexes, `sum` summary offsets, `ax` attachment indexes, `pad` extra bytes in every record).
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    pub features: Vec<String>,
    pub records: Vec<Record>,
}

/// Why a variant is not written.
#[derive(Debug, Clone, PartialEq)]
pub enum Refusal {
    /// The variant asks for something our writer does not do (the suite counts it as unsupported).
    Unsupported(String),
    /// The JSON is not a writer variant.
    Invalid(String),
}

/// The options our writer needs for `features`: uncompressed, every switch as the features say.
pub fn options(features: &[String]) -> Result<McapOptions, Refusal> {
    let off = McapOptions {
        compression: ChunkCompression::None,
        chunks: false,
        message_indexes: false,
        chunk_indexes: false,
        statistics: false,
        summary_schemas: false,
        summary_channels: false,
        metadata_indexes: false,
        summary_offsets: false,
    };
    features.iter().try_fold(off, |mut o, feature| {
        match feature.as_str() {
            "ch" => o.chunks = true,
            "mx" => o.message_indexes = true,
            "st" => o.statistics = true,
            "rsh" => o.summary_schemas = true,
            "rch" => o.summary_channels = true,
            "mdx" => o.metadata_indexes = true,
            "chx" => o.chunk_indexes = true,
            "sum" => o.summary_offsets = true,
            "ax" => return Err(unsupported("attachment indexes: the writer writes no attachments")),
            "pad" => return Err(unsupported("extra bytes after each record's fields, which only a reader test needs")),
            other => return Err(Refusal::Invalid(format!("unknown feature `{other}`"))),
        }
        Ok(o)
    })
}

fn unsupported(why: &str) -> Refusal {
    Refusal::Unsupported(why.to_string())
}

/// A variant from the suite's JSON: `{"records": [{"type": ..., "fields": [[name, value], ...]}, ...], "meta":
/// {"variant": {"features": [...]}}}`, numbers as decimal strings, bytes as arrays of them.
pub fn parse(json: &str) -> Result<Variant, Refusal> {
    let invalid = |what: String| Refusal::Invalid(what);
    let doc: Value = serde_json::from_str(json).map_err(|e| invalid(format!("not JSON: {e}")))?;
    let features = doc["meta"]["variant"]["features"]
        .as_array()
        .ok_or_else(|| invalid("no meta.variant.features list".into()))?
        .iter()
        .map(|f| f.as_str().map(str::to_string).ok_or_else(|| invalid(format!("feature {f} is not a string"))))
        .collect::<Result<Vec<_>, _>>()?;
    let mut records = Vec::new();
    for (k, r) in doc["records"].as_array().ok_or_else(|| invalid("no records list".into()))?.iter().enumerate() {
        let kind = r["type"].as_str().ok_or_else(|| invalid(format!("record {k} has no type")))?;
        if kind == "DataEnd" {
            break;
        }
        let fields = Fields { kind, list: r["fields"].as_array().map(Vec::as_slice).unwrap_or_default() };
        if let Some(record) = fields.record()? {
            records.push(record);
        }
    }
    Ok(Variant { features, records })
}

/// A record's `[name, value]` pairs.
struct Fields<'a> {
    kind: &'a str,
    list: &'a [Value],
}

impl Fields<'_> {
    fn get(&self, name: &str) -> Result<&Value, Refusal> {
        self.list
            .iter()
            .find(|pair| pair[0] == name)
            .map(|pair| &pair[1])
            .ok_or_else(|| Refusal::Invalid(format!("a {} record without `{name}`", self.kind)))
    }

    fn number<T: std::str::FromStr>(&self, name: &str) -> Result<T, Refusal> {
        let v = self.get(name)?;
        v.as_str().and_then(|s| s.parse().ok()).ok_or_else(|| self.bad(name, v))
    }

    fn string(&self, name: &str) -> Result<String, Refusal> {
        let v = self.get(name)?;
        v.as_str().map(str::to_string).ok_or_else(|| self.bad(name, v))
    }

    fn bytes(&self, name: &str) -> Result<Vec<u8>, Refusal> {
        let v = self.get(name)?;
        let items = v.as_array().ok_or_else(|| self.bad(name, v))?;
        items.iter().map(|b| b.as_str().and_then(|s| s.parse().ok()).ok_or_else(|| self.bad(name, v))).collect()
    }

    fn map(&self, name: &str) -> Result<BTreeMap<String, String>, Refusal> {
        let v = self.get(name)?;
        let entries = v.as_object().ok_or_else(|| self.bad(name, v))?;
        entries.iter().map(|(k, x)| Ok((k.clone(), x.as_str().ok_or_else(|| self.bad(name, v))?.to_string()))).collect()
    }

    fn bad(&self, name: &str, v: &Value) -> Refusal {
        Refusal::Invalid(format!("a {} record's `{name}` is {v}, not what MCAP has there", self.kind))
    }

    /// The record to write; `None` for the records a writer derives.
    fn record(&self) -> Result<Option<Record>, Refusal> {
        Ok(Some(match self.kind {
            "Schema" => Record::Schema {
                id: self.number("id")?,
                name: self.string("name")?,
                encoding: self.string("encoding")?,
                data: self.bytes("data")?,
            },
            "Channel" => Record::Channel {
                id: self.number("id")?,
                schema_id: self.number("schema_id")?,
                topic: self.string("topic")?,
                message_encoding: self.string("message_encoding")?,
                metadata: self.map("metadata")?,
            },
            "Message" => Record::Message {
                channel_id: self.number("channel_id")?,
                sequence: self.number("sequence")?,
                log_time_ns: self.number("log_time")?,
                publish_time_ns: self.number("publish_time")?,
                data: self.bytes("data")?,
            },
            "Metadata" => Record::Metadata { name: self.string("name")?, metadata: self.map("metadata")? },
            "Attachment" => return Err(unsupported("an attachment: the writer writes no attachments")),
            "Header" | "DataEnd" | "Footer" | "Statistics" | "ChunkIndex" | "MessageIndex" | "MetadataIndex"
            | "AttachmentIndex" | "SummaryOffset" => return Ok(None),
            other => return Err(Refusal::Invalid(format!("unknown record type `{other}`"))),
        }))
    }
}

/// The file our writer writes for `variant` (profile and library empty, as in the suite's expected files).
pub fn write(variant: &Variant) -> Result<Vec<u8>, Refusal> {
    write_with(variant, options(&variant.features)?)
}

/// The file our writer writes for `variant`'s records with `options` (a compression, say) in place of its features.
pub fn write_with(variant: &Variant, options: McapOptions) -> Result<Vec<u8>, Refusal> {
    let io = |e: std::io::Error| Refusal::Invalid(format!("writing to memory failed: {e}"));
    let mut bytes = Vec::new();
    let mut w = McapWriter::with_options(&mut bytes, "", "", options).map_err(io)?;
    // The variant's ids to the writer's, which numbers schemas and channels itself.
    let (mut schemas, mut channels) = (HashMap::from([(0u16, 0u16)]), HashMap::new());
    let unknown = |what: &str, id: u16| Refusal::Invalid(format!("a {what} id {id} no earlier record added"));
    for record in &variant.records {
        match record {
            Record::Schema { id, name, encoding, data } => {
                schemas.insert(*id, w.add_schema(name, encoding, data));
            }
            Record::Channel { id, schema_id, topic, message_encoding, metadata } => {
                let schema = *schemas.get(schema_id).ok_or_else(|| unknown("schema", *schema_id))?;
                channels.insert(*id, w.add_channel(schema, topic, message_encoding, metadata));
            }
            Record::Message { channel_id, sequence, log_time_ns, publish_time_ns, data } => {
                let channel = *channels.get(channel_id).ok_or_else(|| unknown("channel", *channel_id))?;
                w.write_message_numbered(channel, *sequence, *log_time_ns, *publish_time_ns, data).map_err(io)?;
            }
            Record::Metadata { name, metadata } => w.write_metadata(name, metadata).map_err(io)?,
        }
    }
    w.finish().map_err(io)?;
    drop(w);
    Ok(bytes)
}
