//! The MCAP file format as the logger writes it (<https://mcap.dev/spec>): chunked, indexed, with a summary. A
//! message is copied into the open chunk's buffer as it comes, and a chunk is compressed in one call when it is
//! closed, without LZ4's content checksum (the chunk record has its own CRC): the `mcap` crate's writer compresses
//! each record field by field as it is written and checksums the LZ4 frame again, which was half the logger's work a
//! lockstep tick. Reading stays with the `mcap` crate ([`super::reader`]), and Foxglove's readers check what this
//! writes in the recording tests.
//!
//! The logger writes every index and summary group; [`McapOptions`] can leave each out, as the MCAP project's
//! conformance suite does in its writer variants: `tests/mcap_conformance.rs` holds this writer, so configured, to
//! the bytes of the `mcap` crate's writer (one of the suite's reference writers), and
//! `examples/mcap_conformance_writer/` runs it against the suite itself.

use std::io::Write;

/// The file's first and last bytes.
const MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// Record opcodes.
mod op {
    pub const HEADER: u8 = 0x01;
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const MESSAGE_INDEX: u8 = 0x07;
    pub const CHUNK_INDEX: u8 = 0x08;
    pub const STATISTICS: u8 = 0x0B;
    pub const METADATA: u8 = 0x0C;
    pub const METADATA_INDEX: u8 = 0x0D;
    pub const SUMMARY_OFFSET: u8 = 0x0E;
    pub const DATA_END: u8 = 0x0F;
}

/// A chunk is closed before a message once its records are over this many bytes (the `mcap` crate's default and
/// rule), or at a flush.
pub const CHUNK_SIZE: usize = 1024 * 1024;

/// How chunks are compressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkCompression {
    /// Stored as they are.
    None,
    /// LZ4 frames: the cheapest per byte.
    Lz4,
    /// Zstandard frames at this level: the smaller file.
    Zstd(i32),
}

/// What a file holds besides its records: [`McapOptions::indexed`] is everything, what the logger writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct McapOptions {
    /// How chunks are compressed.
    pub compression: ChunkCompression,
    /// Schemas, channels and messages in chunks; `false`: straight in the data section, with no index.
    pub chunks: bool,
    /// A message index per channel after each chunk.
    pub message_indexes: bool,
    /// The chunk indexes in the summary.
    pub chunk_indexes: bool,
    /// The statistics record in the summary.
    pub statistics: bool,
    /// Every schema again in the summary.
    pub summary_schemas: bool,
    /// Every channel again in the summary.
    pub summary_channels: bool,
    /// The metadata indexes in the summary.
    pub metadata_indexes: bool,
    /// Where each summary group starts, after the summary.
    pub summary_offsets: bool,
}

impl McapOptions {
    /// Chunks compressed by `compression`, and every index and summary group.
    pub fn indexed(compression: ChunkCompression) -> Self {
        Self {
            compression,
            chunks: true,
            message_indexes: true,
            chunk_indexes: true,
            statistics: true,
            summary_schemas: true,
            summary_channels: true,
            metadata_indexes: true,
            summary_offsets: true,
        }
    }
}

/// Little-endian MCAP fields appended to a byte buffer.
trait Fields {
    fn u16(&mut self, v: u16);
    fn u32(&mut self, v: u32);
    fn u64(&mut self, v: u64);
    /// A string: its byte length (u32), then its bytes.
    fn str(&mut self, s: &str);
    /// A record: opcode, the content's length (u64), the content `body` writes.
    fn record(&mut self, opcode: u8, body: impl FnOnce(&mut Vec<u8>));
    /// A map or array: its byte length (u32), then what `body` writes.
    fn prefixed(&mut self, body: impl FnOnce(&mut Vec<u8>));
}

impl Fields for Vec<u8> {
    fn u16(&mut self, v: u16) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.extend_from_slice(s.as_bytes());
    }
    fn record(&mut self, opcode: u8, body: impl FnOnce(&mut Vec<u8>)) {
        self.push(opcode);
        let at = self.len();
        self.u64(0);
        body(self);
        let length = (self.len() - at - 8) as u64;
        self[at..at + 8].copy_from_slice(&length.to_le_bytes());
    }
    fn prefixed(&mut self, body: impl FnOnce(&mut Vec<u8>)) {
        let at = self.len();
        self.u32(0);
        body(self);
        let length = (self.len() - at - 4) as u32;
        self[at..at + 4].copy_from_slice(&length.to_le_bytes());
    }
}

fn string_map(buf: &mut Vec<u8>, map: &std::collections::BTreeMap<String, String>) {
    buf.prefixed(|b| {
        for (k, v) in map {
            b.str(k);
            b.str(v);
        }
    });
}

/// The LZ4 frame descriptor: version 1, independent blocks, no block or content checksum, no content size (FLG);
/// blocks of up to 4 MB (BD); the descriptor's checksum, the second byte of XXH32 of the two bytes before it (HC).
const LZ4_FRAME_START: [u8; 7] = [0x04, 0x22, 0x4D, 0x18, 0x60, 0x70, 0x73];
const LZ4_BLOCK_MAX: usize = 4 << 20;

/// `data` as one LZ4 frame (what MCAP's `lz4` chunks hold) in `out`: a block compressed in one call per 4 MB, with
/// no checksum (the chunk record has a CRC of the uncompressed records) and no per-call context to allocate.
fn lz4_frame(data: &[u8], out: &mut Vec<u8>) -> std::io::Result<()> {
    out.clear();
    out.extend_from_slice(&LZ4_FRAME_START);
    for block in data.chunks(LZ4_BLOCK_MAX) {
        let at = out.len();
        out.resize(at + 4 + lz4::block::compress_bound(block.len())?, 0);
        let size = lz4::block::compress_to_buffer(block, None, false, &mut out[at + 4..])?;
        let size = if size == 0 || size >= block.len() {
            // Incompressible: stored as it is, which the size's high bit says.
            out.truncate(at + 4);
            out.extend_from_slice(block);
            block.len() as u32 | 0x8000_0000
        } else {
            out.truncate(at + 4 + size);
            size as u32
        };
        out[at..at + 4].copy_from_slice(&size.to_le_bytes());
    }
    out.extend_from_slice(&0u32.to_le_bytes());
    Ok(())
}

/// Widen `bounds` (first, last log time) to include `t`.
fn widen(bounds: &mut Option<(u64, u64)>, t: u64) {
    *bounds = Some(bounds.map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
}

/// An MCAP file being written to `out`.
pub struct McapWriter<W: Write> {
    out: W,
    options: McapOptions,
    /// Bytes handed to `out`.
    written: u64,
    /// CRC-32 of the data section so far (from the magic on, as the `mcap` crate counts it).
    data_crc: crc32fast::Hasher,
    /// Zstandard's context, kept from chunk to chunk; `None`: another compression.
    zstd: Option<zstd::bulk::Compressor<'static>>,
    /// The open chunk's records, uncompressed (without chunks: the records not yet handed to `out`).
    chunk: Vec<u8>,
    /// First and last log time of the open chunk's messages.
    chunk_bounds: Option<(u64, u64)>,
    /// The open chunk's message index entries (log time, offset in the chunk), by channel id.
    chunk_entries: Vec<Vec<(u64, u64)>>,
    /// The closed chunk, compressed (reused).
    compressed: Vec<u8>,
    /// Records being assembled outside the hot path (reused).
    scratch: Vec<u8>,
    /// Schema records, for the summary; a schema's id is its position + 1.
    schemas: Vec<Vec<u8>>,
    /// Channel records, for the summary; a channel's id is its position + 1.
    channels: Vec<Vec<u8>>,
    /// Messages written, by channel id.
    message_counts: Vec<u64>,
    /// First and last log time of every message.
    bounds: Option<(u64, u64)>,
    /// Chunk index records, for the summary.
    chunk_indexes: Vec<u8>,
    chunk_count: u32,
    /// Metadata index records, for the summary.
    metadata_indexes: Vec<u8>,
    metadata_count: u32,
    finished: bool,
}

impl<W: Write> McapWriter<W> {
    /// Start a file the logger's way (chunks, every index and summary group): the magic and the header record.
    pub fn new(out: W, profile: &str, library: &str, compression: ChunkCompression) -> std::io::Result<Self> {
        Self::with_options(out, profile, library, McapOptions::indexed(compression))
    }

    /// Start a file holding what `options` say: the magic and the header record.
    pub fn with_options(out: W, profile: &str, library: &str, options: McapOptions) -> std::io::Result<Self> {
        let zstd = match options.compression {
            ChunkCompression::Zstd(level) => Some(zstd::bulk::Compressor::new(level)?),
            ChunkCompression::Lz4 | ChunkCompression::None => None,
        };
        let mut writer = Self {
            out,
            options,
            written: 0,
            data_crc: crc32fast::Hasher::new(),
            zstd,
            chunk: Vec::with_capacity(CHUNK_SIZE + 64 * 1024),
            chunk_bounds: None,
            chunk_entries: Vec::new(),
            compressed: Vec::new(),
            scratch: Vec::new(),
            schemas: Vec::new(),
            channels: Vec::new(),
            message_counts: Vec::new(),
            bounds: None,
            chunk_indexes: Vec::new(),
            chunk_count: 0,
            metadata_indexes: Vec::new(),
            metadata_count: 0,
            finished: false,
        };
        let mut start = MAGIC.to_vec();
        start.record(op::HEADER, |b| {
            b.str(profile);
            b.str(library);
        });
        writer.emit(&start)?;
        Ok(writer)
    }

    /// Write `bytes` to the data section.
    fn emit(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.out.write_all(bytes)?;
        self.data_crc.update(bytes);
        self.written += bytes.len() as u64;
        Ok(())
    }

    /// The id of a schema with this content, added (into the open chunk, and to the summary) if it is new.
    pub fn add_schema(&mut self, name: &str, encoding: &str, data: &[u8]) -> u16 {
        let id = self.schemas.len() as u16 + 1;
        let mut record = Vec::new();
        record.record(op::SCHEMA, |b| {
            b.u16(id);
            b.str(name);
            b.str(encoding);
            b.u32(data.len() as u32);
            b.extend_from_slice(data);
        });
        // The same record but for the id (after the opcode and the length): the same schema.
        const ID: std::ops::Range<usize> = 9..11;
        let same = |known: &Vec<u8>| known[..ID.start] == record[..ID.start] && known[ID.end..] == record[ID.end..];
        if let Some(k) = self.schemas.iter().position(same) {
            return k as u16 + 1;
        }
        self.chunk.extend_from_slice(&record);
        self.schemas.push(record);
        id
    }

    /// A new channel's id; its record goes into the open chunk, and to the summary.
    pub fn add_channel(
        &mut self,
        schema_id: u16,
        topic: &str,
        message_encoding: &str,
        metadata: &std::collections::BTreeMap<String, String>,
    ) -> u16 {
        let id = self.channels.len() as u16 + 1;
        let mut record = Vec::new();
        record.record(op::CHANNEL, |b| {
            b.u16(id);
            b.u16(schema_id);
            b.str(topic);
            b.str(message_encoding);
            string_map(b, metadata);
        });
        self.chunk.extend_from_slice(&record);
        self.channels.push(record);
        self.message_counts.resize(usize::from(id) + 1, 0);
        self.chunk_entries.resize_with(usize::from(id) + 1, Vec::new);
        id
    }

    /// A metadata record, outside any chunk (the open one is closed first).
    pub fn write_metadata(
        &mut self,
        name: &str,
        metadata: &std::collections::BTreeMap<String, String>,
    ) -> std::io::Result<()> {
        self.close_chunk()?;
        let mut record = Vec::new();
        record.record(op::METADATA, |b| {
            b.str(name);
            string_map(b, metadata);
        });
        let offset = self.written;
        self.emit(&record)?;
        self.metadata_indexes.record(op::METADATA_INDEX, |b| {
            b.u64(offset);
            b.u64(record.len() as u64);
            b.str(name);
        });
        self.metadata_count += 1;
        Ok(())
    }

    /// The index of a channel [`Self::add_channel`] gave, in the per-channel tables.
    fn channel_index(&self, channel: u16) -> usize {
        let id = usize::from(channel);
        assert!(id >= 1 && id < self.message_counts.len(), "message on channel {channel}, which was never added");
        id
    }

    /// A message on `channel` (an id [`Self::add_channel`] gave), numbered 1, 2, ... on its channel (MCAP's
    /// `sequence`); see [`Self::write_message_numbered`].
    pub fn write_message(
        &mut self,
        channel: u16,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> std::io::Result<()> {
        let sequence = (self.message_counts[self.channel_index(channel)] + 1) as u32;
        self.write_message_numbered(channel, sequence, log_time_ns, publish_time_ns, data)
    }

    /// A message on `channel` with the `sequence` number its source gave it, copied into the open chunk; the chunk
    /// is closed and written first if it is already over [`CHUNK_SIZE`].
    pub fn write_message_numbered(
        &mut self,
        channel: u16,
        sequence: u32,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> std::io::Result<()> {
        let id = self.channel_index(channel);
        if self.chunk.len() > CHUNK_SIZE {
            self.close_chunk()?;
        }
        let offset = self.chunk.len() as u64;
        let c = &mut self.chunk;
        c.push(op::MESSAGE);
        c.u64((2 + 4 + 8 + 8 + data.len()) as u64);
        c.u16(channel);
        c.u32(sequence);
        c.u64(log_time_ns);
        c.u64(publish_time_ns);
        c.extend_from_slice(data);
        if self.options.chunks && self.options.message_indexes {
            self.chunk_entries[id].push((log_time_ns, offset));
        }
        self.message_counts[id] += 1;
        widen(&mut self.chunk_bounds, log_time_ns);
        widen(&mut self.bounds, log_time_ns);
        Ok(())
    }

    /// Write the open chunk's records: compressed into a chunk with its message indexes after it, or, without
    /// chunks, as they are.
    fn close_chunk(&mut self) -> std::io::Result<()> {
        if self.chunk.is_empty() {
            return Ok(());
        }
        if !self.options.chunks {
            let records = std::mem::take(&mut self.chunk);
            let written = self.emit(&records);
            self.chunk = records;
            self.chunk.clear();
            self.chunk_bounds = None;
            return written;
        }
        let uncompressed_crc = crc32fast::hash(&self.chunk);
        let name = self.compress()?;
        let (start, end) = self.chunk_bounds.take().unwrap_or((0, 0));
        let chunk_start = self.written;
        let mut header = std::mem::take(&mut self.scratch);
        header.clear();
        header.push(op::CHUNK);
        let content = 8 + 8 + 8 + 4 + 4 + name.len() + 8 + self.compressed.len();
        header.u64(content as u64);
        header.u64(start);
        header.u64(end);
        header.u64(self.chunk.len() as u64);
        header.u32(uncompressed_crc);
        header.str(name);
        header.u64(self.compressed.len() as u64);
        let compressed = std::mem::take(&mut self.compressed);
        let written = self.emit(&header).and_then(|()| self.emit(&compressed));
        self.compressed = compressed;
        self.scratch = header;
        written?;
        let chunk_length = self.written - chunk_start;
        let (offsets, index_length) = self.write_message_indexes()?;
        self.chunk_indexes.record(op::CHUNK_INDEX, |b| {
            b.u64(start);
            b.u64(end);
            b.u64(chunk_start);
            b.u64(chunk_length);
            b.prefixed(|b| {
                for &(id, offset) in &offsets {
                    b.u16(id);
                    b.u64(offset);
                }
            });
            b.u64(index_length);
            b.str(name);
            b.u64(self.compressed.len() as u64);
            b.u64(self.chunk.len() as u64);
        });
        self.chunk_count += 1;
        self.chunk.clear();
        Ok(())
    }

    /// The open chunk's records compressed into `self.compressed`; the compression's name in MCAP.
    fn compress(&mut self) -> std::io::Result<&'static str> {
        self.compressed.clear();
        match self.options.compression {
            ChunkCompression::Zstd(_) => {
                let z = self.zstd.as_mut().expect("a zstd context, made with the options");
                self.compressed.reserve(zstd::zstd_safe::compress_bound(self.chunk.len()));
                z.compress_to_buffer(&self.chunk[..], &mut self.compressed)?;
                Ok("zstd")
            }
            ChunkCompression::Lz4 => {
                lz4_frame(&self.chunk, &mut self.compressed)?;
                Ok("lz4")
            }
            ChunkCompression::None => {
                self.compressed.extend_from_slice(&self.chunk);
                Ok("")
            }
        }
    }

    /// The closed chunk's message indexes, by channel id: where each is, and their length in all.
    fn write_message_indexes(&mut self) -> std::io::Result<(Vec<(u16, u64)>, u64)> {
        let mut indexes = std::mem::take(&mut self.scratch);
        indexes.clear();
        let mut offsets = Vec::new();
        for (id, entries) in self.chunk_entries.iter_mut().enumerate().filter(|(_, e)| !e.is_empty()) {
            offsets.push((id as u16, self.written + indexes.len() as u64));
            indexes.record(op::MESSAGE_INDEX, |b| {
                b.u16(id as u16);
                b.prefixed(|b| {
                    for &(t, offset) in entries.iter() {
                        b.u64(t);
                        b.u64(offset);
                    }
                });
            });
            entries.clear();
        }
        let written = self.emit(&indexes);
        let length = indexes.len() as u64;
        self.scratch = indexes;
        written.map(|()| (offsets, length))
    }

    /// Close the open chunk and hand everything to the file: a reader reads up to here if the writer dies next.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.close_chunk()?;
        self.out.flush()
    }

    /// Close the data section and write the summary (the groups the options keep: schemas, channels, statistics,
    /// chunk and metadata indexes), its offsets, the footer and the closing magic. Once only; later calls do nothing.
    pub fn finish(&mut self) -> std::io::Result<()> {
        if self.finished {
            return Ok(());
        }
        self.close_chunk()?;
        self.finished = true;
        let data_crc = self.data_crc.clone().finalize();
        let mut end = Vec::new();
        end.record(op::DATA_END, |b| b.u32(data_crc));
        self.emit(&end)?;
        let summary_start = self.written;
        let mut summary = Vec::new();
        let mut offsets = Vec::new();
        let mut group = |summary: &mut Vec<u8>, keep: bool, opcode: u8, records: &[u8]| {
            if keep && !records.is_empty() {
                offsets.push((opcode, summary_start + summary.len() as u64, records.len() as u64));
                summary.extend_from_slice(records);
            }
        };
        let o = self.options;
        group(&mut summary, o.summary_schemas, op::SCHEMA, &self.schemas.concat());
        group(&mut summary, o.summary_channels, op::CHANNEL, &self.channels.concat());
        group(&mut summary, o.statistics, op::STATISTICS, &self.statistics());
        group(&mut summary, o.chunk_indexes, op::CHUNK_INDEX, &self.chunk_indexes);
        group(&mut summary, o.metadata_indexes, op::METADATA_INDEX, &self.metadata_indexes);
        // As the `mcap` crate writes them: no summary, a summary start of 0; no offsets, an offset start of 0.
        let groups_end = summary_start + summary.len() as u64;
        let summary_offset_start = if o.summary_offsets { groups_end } else { 0 };
        if o.summary_offsets {
            for (opcode, start, length) in offsets {
                summary.record(op::SUMMARY_OFFSET, |b| {
                    b.push(opcode);
                    b.u64(start);
                    b.u64(length);
                });
            }
        }
        // The footer's CRC covers the summary and the footer up to the CRC itself.
        summary.push(op::FOOTER);
        summary.u64(8 + 8 + 4);
        summary.u64(if groups_end > summary_start { summary_start } else { 0 });
        summary.u64(summary_offset_start);
        let summary_crc = crc32fast::hash(&summary);
        summary.u32(summary_crc);
        summary.extend_from_slice(MAGIC);
        self.out.write_all(&summary)?;
        self.written += summary.len() as u64;
        self.out.flush()
    }

    /// The statistics record of everything written.
    fn statistics(&self) -> Vec<u8> {
        let mut statistics = Vec::new();
        let (first, last) = self.bounds.unwrap_or((0, 0));
        statistics.record(op::STATISTICS, |b| {
            b.u64(self.message_counts.iter().sum());
            b.u16(self.schemas.len() as u16);
            b.u32(self.channels.len() as u32);
            b.u32(0);
            b.u32(self.metadata_count);
            b.u32(self.chunk_count);
            b.u64(first);
            b.u64(last);
            b.prefixed(|b| {
                for (id, &count) in self.message_counts.iter().enumerate().filter(|(_, c)| **c > 0) {
                    b.u16(id as u16);
                    b.u64(count);
                }
            });
        });
        statistics
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A file with two channels, metadata and more than one chunk, as the `mcap` crate reads it.
    fn written(compression: ChunkCompression) -> Vec<u8> {
        let mut w = McapWriter::new(Vec::new(), "", "test", compression).unwrap();
        let schema = w.add_schema("s/msg/A", "ros2msg", b"float64 x\n");
        assert_eq!(w.add_schema("s/msg/A", "ros2msg", b"float64 x\n"), schema, "the same schema twice: one id");
        let meta = BTreeMap::from([("k".to_string(), "v".to_string())]);
        let a = w.add_channel(schema, "/a", "cdr", &meta);
        let b = w.add_channel(0, "/b", "json", &BTreeMap::new());
        w.write_metadata("run", &meta).unwrap();
        let payload = vec![7u8; 3000];
        for k in 0..1000u64 {
            w.write_message(a, 1_000 + k, 900 + k, &payload).unwrap();
            if k % 10 == 0 {
                w.write_message(b, 1_000 + k, 1_000 + k, b"{}").unwrap();
            }
            if k == 500 {
                w.flush().unwrap();
            }
        }
        w.finish().unwrap();
        w.finish().unwrap();
        w.out
    }

    #[test]
    fn lz4_frames_decode_with_liblz4_compressible_or_not() {
        let text: Vec<u8> = (0..5_000_000u32).flat_map(|k| ((k / 7) as u16).to_le_bytes()).collect();
        let noise: Vec<u8> = (0..70_000u64).map(|k| (k.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 56) as u8).collect();
        for data in [&text[..], &noise[..], &[][..]] {
            let mut frame = Vec::new();
            lz4_frame(data, &mut frame).unwrap();
            let mut decoded = Vec::new();
            std::io::Read::read_to_end(&mut lz4::Decoder::new(&frame[..]).unwrap(), &mut decoded).unwrap();
            assert!(decoded == data, "{} bytes back of {}", decoded.len(), data.len());
        }
    }

    #[test]
    fn the_mcap_crate_reads_back_every_message_with_its_summary_and_indexes() {
        for compression in [ChunkCompression::Lz4, ChunkCompression::Zstd(1)] {
            let bytes = written(compression);
            let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
            let stats = summary.stats.as_ref().unwrap();
            assert_eq!((stats.message_count, stats.channel_count, stats.schema_count), (1100, 2, 1));
            assert_eq!((stats.message_start_time, stats.message_end_time, stats.metadata_count), (1000, 1999, 1));
            assert!(summary.chunk_indexes.len() >= 3, "{compression:?}: {} chunks", summary.chunk_indexes.len());
            assert_eq!(summary.channels[&1].topic, "/a");
            assert_eq!(summary.channels[&1].metadata["k"], "v");
            assert_eq!(summary.metadata_indexes[0].name, "run");
            // Through the indexes, as an indexed reader (Foxglove's) does.
            let mut indexed = 0;
            // The first chunk has the schema and the channels only: no message indexes (as the `mcap` crate writes).
            assert!(summary.chunk_indexes[0].message_index_offsets.is_empty());
            for chunk in &summary.chunk_indexes[1..] {
                let indexes = summary.read_message_indexes(&bytes, chunk).unwrap();
                for (channel, entries) in indexes {
                    for entry in entries {
                        let m = summary.seek_message(&bytes, chunk, &entry).unwrap();
                        assert_eq!(m.channel.id, channel.id);
                        assert_eq!(m.log_time, entry.log_time);
                        indexed += 1;
                    }
                }
            }
            assert_eq!(indexed, 1100);
            // And straight through, checking every CRC.
            let messages: Vec<_> = mcap::MessageStream::new(&bytes).unwrap().map(|m| m.unwrap()).collect();
            assert_eq!(messages.len(), 1100);
            assert_eq!(messages[0].data.len(), 3000);
            assert_eq!((messages[1].channel.topic.as_str(), messages[1].sequence), ("/b", 1));
            assert_eq!(messages.last().unwrap().publish_time, 1899);
        }
    }
}
