//! Walking a recording's records so that damage loses only what is damaged.
//!
//! MCAP's own readers stop at the first bad chunk. This walker reads the data section record by
//! record: a chunk is decompressed and its CRC checked before any of its records is handed out,
//! and a chunk (or attachment, or other record) that fails is skipped, reported as a
//! [`Damage`], and reading goes on with the next good record. The next record is found by the
//! damaged record's own length when a plausible record starts there; else at the next record the
//! summary's indexes name (when the footer and summary are intact); else by scanning forward for
//! a chunk or attachment whose CRC checks. A file that simply ends (a killed run) is cut off,
//! not damaged.

use mcap::records::{op, Record};
use mcap::sans_io::linear_reader::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

/// Bigger records than this are taken as damage (a recording's chunks are about 1 MiB).
pub const RECORD_LIMIT: u64 = 1 << 30;

/// Opcode and length in front of every record.
const RECORD_HEAD: u64 = 9;

/// A part of the file that could not be read and was skipped.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Damage {
    /// Where the damaged record starts (bytes from the start of the file).
    pub offset: u64,
    /// Bytes skipped from `offset` up to the next good record.
    pub skipped: u64,
    /// What the record was (`chunk`, `attachment`, `record`).
    pub what: &'static str,
    /// Why it could not be read (`CRC mismatch`, `does not decompress: ...`).
    pub reason: String,
}

impl std::fmt::Display for Damage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} at byte {} is damaged ({}; {} bytes skipped)",
            self.what, self.offset, self.reason, self.skipped
        )
    }
}

/// What [`Scanner::next_event`] hands out.
pub enum Event {
    /// A good record (a chunk's records come one by one, once the whole chunk checked out).
    Record(Record<'static>),
    /// A damaged stretch, skipped.
    Damaged(Damage),
}

/// Reads a recording's data section record by record (see the module doc).
pub struct Scanner {
    file: BufReader<File>,
    len: u64,
    pos: u64,
    /// Offsets of records the summary names (chunks, attachments, metadata), ascending.
    indexed: Vec<u64>,
    /// The summary's schema and channel records (for messages whose own were damaged).
    summary_channels: Vec<Record<'static>>,
    pending: VecDeque<Record<'static>>,
    /// `Some(reason)` once the file turned out to be cut off.
    truncated: Option<String>,
    done: bool,
}

impl Scanner {
    /// A scanner of `file`, whose first 8 bytes (the magic) were checked by the caller.
    pub fn new(file: File) -> std::io::Result<Scanner> {
        let len = file.metadata()?.len();
        let mut s = Scanner {
            file: BufReader::with_capacity(1 << 16, file),
            len,
            pos: mcap::MAGIC.len() as u64,
            indexed: Vec::new(),
            summary_channels: Vec::new(),
            pending: VecDeque::new(),
            truncated: None,
            done: false,
        };
        if let Some((indexed, channels)) = s.summary() {
            (s.indexed, s.summary_channels) = (indexed, channels);
        }
        s.file.seek(SeekFrom::Start(s.pos))?;
        Ok(s)
    }

    /// The summary's schema and channel records (empty without an intact summary).
    pub fn summary_channels(&self) -> &[Record<'static>] {
        &self.summary_channels
    }

    /// `Some(reason)` when the file ended before its data section did (a cut-off file).
    pub fn truncated(&self) -> Option<&str> {
        self.truncated.as_deref()
    }

    /// The next good record or damaged stretch; `None` at the end of the data section.
    pub fn next_event(&mut self) -> std::io::Result<Option<Event>> {
        loop {
            if let Some(r) = self.pending.pop_front() {
                return Ok(Some(Event::Record(r)));
            }
            if self.done {
                return Ok(None);
            }
            let start = self.pos;
            let Some((opcode, length)) = self.head_at(start)? else {
                self.cut_off(start, "the file ends in the middle of a record");
                continue;
            };
            let end = start.saturating_add(RECORD_HEAD).saturating_add(length);
            let plausible = opcode_known(opcode) && length <= RECORD_LIMIT;
            if !plausible || end > self.len {
                // A record longer than the rest of the file is the last one of a cut-off file,
                // unless good records follow (then its header was damaged).
                if plausible {
                    if let Some(next) = self.resync(start)? {
                        return Ok(Some(self.damaged(
                            start,
                            next,
                            "record",
                            "its length is wrong",
                        )));
                    }
                    self.cut_off(start, "the file ends in the middle of a record");
                    continue;
                }
                let next = self.resync(start)?.unwrap_or(self.len);
                if next >= self.len {
                    self.done = true;
                    self.truncated = Some(format!(
                        "damaged data from byte {start} to the end of the file"
                    ));
                }
                return Ok(Some(self.damaged(
                    start,
                    next,
                    "record",
                    &format!("unknown record type {opcode:#04x}"),
                )));
            }
            let body = self.body(start, length)?;
            self.pos = end;
            match opcode {
                op::DATA_END | op::FOOTER => {
                    self.done = true;
                    continue;
                }
                op::MESSAGE_INDEX
                | op::CHUNK_INDEX
                | op::ATTACHMENT_INDEX
                | op::METADATA_INDEX
                | op::STATISTICS
                | op::SUMMARY_OFFSET
                | op::HEADER => continue,
                _ => {}
            }
            let what = match opcode {
                op::CHUNK => "chunk",
                op::ATTACHMENT => "attachment",
                _ => "record",
            };
            match read_record(opcode, &body) {
                Ok(records) => self.pending.extend(records),
                Err(reason) => {
                    let next = if self.follows_well(end)? {
                        Some(end)
                    } else {
                        self.resync(start)?
                    };
                    let next = next.unwrap_or(self.len);
                    if next >= self.len {
                        self.done = true;
                    }
                    return Ok(Some(self.damaged(start, next, what, &reason)));
                }
            }
        }
    }

    /// True when a record that fits the file starts at `at` (and reads whole, if it is a chunk
    /// or attachment), so a damaged record's own length can be trusted to reach it.
    fn follows_well(&mut self, at: u64) -> std::io::Result<bool> {
        match self.head_at(at)? {
            Some((op::CHUNK | op::ATTACHMENT, _)) => self.good_at(at, false),
            Some((o, l)) => {
                Ok(opcode_known(o) && at.saturating_add(RECORD_HEAD).saturating_add(l) <= self.len)
            }
            None => Ok(at == self.len),
        }
    }

    fn cut_off(&mut self, at: u64, why: &str) {
        self.done = true;
        if at < self.len {
            self.truncated = Some(format!(
                "{why} at byte {at} of {} (cut off: a crash or a kill?)",
                self.len
            ));
        } else {
            self.truncated = Some(format!(
                "the file ends after {} bytes, before its summary (cut off: a crash or a kill?)",
                self.len
            ));
        }
    }

    fn damaged(&mut self, start: u64, next: u64, what: &'static str, reason: &str) -> Event {
        self.pos = next;
        let _ = self.file.seek(SeekFrom::Start(next));
        Event::Damaged(Damage {
            offset: start,
            skipped: next - start,
            what,
            reason: reason.to_string(),
        })
    }

    /// Opcode and length of the record at `at`, or `None` if the file ends first.
    fn head_at(&mut self, at: u64) -> std::io::Result<Option<(u8, u64)>> {
        if at.saturating_add(RECORD_HEAD) > self.len {
            return Ok(None);
        }
        self.file.seek(SeekFrom::Start(at))?;
        let mut head = [0u8; RECORD_HEAD as usize];
        self.file.read_exact(&mut head)?;
        let mut len = [0u8; 8];
        len.copy_from_slice(&head[1..]);
        Ok(Some((head[0], u64::from_le_bytes(len))))
    }

    fn body(&mut self, start: u64, length: u64) -> std::io::Result<Vec<u8>> {
        self.file.seek(SeekFrom::Start(start + RECORD_HEAD))?;
        let mut body = vec![0u8; length as usize];
        self.file.read_exact(&mut body)?;
        Ok(body)
    }

    /// The start of the next good chunk or attachment after `start`: one the summary names,
    /// else one found by scanning forward (its CRC checked). `None` when there is none.
    fn resync(&mut self, start: u64) -> std::io::Result<Option<u64>> {
        for at in self.indexed.clone() {
            if at > start && self.good_at(at, true)? {
                return Ok(Some(at));
            }
        }
        // Windows overlap by a chunk header, so a header cut by a window's end is seen whole in
        // the next one.
        const OVERLAP: usize = 64;
        let mut at = start + 1;
        let mut window = vec![0u8; 1 << 16];
        while at + RECORD_HEAD <= self.len {
            self.file.seek(SeekFrom::Start(at))?;
            let n = read_some(&mut self.file, &mut window)?;
            let last = at + n as u64 >= self.len;
            let usable = if last { n } else { n.saturating_sub(OVERLAP) };
            for i in 0..usable {
                let here = at + i as u64;
                if plausible_head(&window[i..n], here, self.len) && self.good_at(here, false)? {
                    return Ok(Some(here));
                }
            }
            if last || usable == 0 {
                break;
            }
            at += usable as u64;
        }
        Ok(None)
    }

    /// True when a chunk or attachment (or, with `metadata`, a metadata record) that reads whole,
    /// CRC and all, starts at `at`.
    fn good_at(&mut self, at: u64, metadata: bool) -> std::io::Result<bool> {
        let Some((opcode, length)) = self.head_at(at)? else {
            return Ok(false);
        };
        let kind_ok =
            matches!(opcode, op::CHUNK | op::ATTACHMENT) || (metadata && opcode == op::METADATA);
        if !kind_ok || length > RECORD_LIMIT || at + RECORD_HEAD + length > self.len {
            return Ok(false);
        }
        let body = self.body(at, length)?;
        Ok(read_record(opcode, &body).is_ok())
    }

    /// Offsets of the records the summary section indexes, and its schemas and channels, if
    /// the footer and summary read.
    fn summary(&mut self) -> Option<(Vec<u64>, Vec<Record<'static>>)> {
        const FOOTER: u64 = RECORD_HEAD + 20;
        let magic = mcap::MAGIC.len() as u64;
        if self.len < magic * 2 + FOOTER {
            return None;
        }
        let footer_at = self.len - magic - FOOTER;
        let (opcode, length) = self.head_at(footer_at).ok()??;
        if opcode != op::FOOTER || length != 20 {
            return None;
        }
        let body = self.body(footer_at, length).ok()?;
        let Ok(Record::Footer(footer)) = mcap::parse_record(op::FOOTER, &body) else {
            return None;
        };
        let (mut at, stop) = (footer.summary_start, footer_at);
        if at == 0 || at >= stop {
            return None;
        }
        let mut offsets = Vec::new();
        let mut channels = Vec::new();
        while at < stop {
            let (opcode, length) = self.head_at(at).ok()??;
            if length > stop - at {
                return None;
            }
            let body = self.body(at, length).ok()?;
            match mcap::parse_record(opcode, &body).ok()? {
                Record::ChunkIndex(c) => offsets.push(c.chunk_start_offset),
                Record::AttachmentIndex(a) => offsets.push(a.offset),
                Record::MetadataIndex(m) => offsets.push(m.offset),
                r @ (Record::Schema { .. } | Record::Channel(_)) => channels.push(r.into_owned()),
                _ => {}
            }
            at += RECORD_HEAD + length;
        }
        offsets.sort_unstable();
        Some((offsets, channels))
    }
}

fn opcode_known(opcode: u8) -> bool {
    (op::HEADER..=op::DATA_END).contains(&opcode)
}

/// Reads until `buf` is full or the file ends; the bytes read.
pub(super) fn read_some(file: &mut impl Read, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match file.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

/// True when `bytes` (the file from `at` on) may start a chunk or attachment: the opcode, a
/// length that fits in the file and, for a chunk, a compressed size that with the header fills
/// the record (a chunk's header: three u64, a u32 CRC, the compression name as a u32 length and
/// its bytes, then the compressed size as u64). This rules out almost every chance match before
/// anything is decompressed.
fn plausible_head(bytes: &[u8], at: u64, file_len: u64) -> bool {
    let u64_at = |i: usize| -> Option<u64> {
        Some(u64::from_le_bytes(bytes.get(i..i + 8)?.try_into().ok()?))
    };
    let Some(&opcode) = bytes.first() else {
        return false;
    };
    if opcode != op::CHUNK && opcode != op::ATTACHMENT {
        return false;
    }
    let Some(length) = u64_at(1) else {
        return false;
    };
    if length > RECORD_LIMIT || at + RECORD_HEAD + length > file_len {
        return false;
    }
    if opcode == op::ATTACHMENT {
        return true;
    }
    let fixed = RECORD_HEAD as usize + 8 * 3 + 4;
    let Some(name_len) = bytes
        .get(fixed..fixed + 4)
        .and_then(|b| b.try_into().ok())
        .map(|b| u32::from_le_bytes(b) as u64)
    else {
        return false;
    };
    if name_len > 16 {
        return false;
    }
    let Some(compressed) = u64_at(fixed + 4 + name_len as usize) else {
        return false;
    };
    let header = (fixed as u64 - RECORD_HEAD) + 4 + name_len + 8;
    header.checked_add(compressed) == Some(length)
}

/// The records of one top-level record: a chunk's records (all of them, once its CRC checked),
/// or the record itself. `Err(reason)` when it is damaged.
fn read_record(opcode: u8, body: &[u8]) -> Result<Vec<Record<'static>>, String> {
    if opcode == op::ATTACHMENT && !attachment_fits(body) {
        return Err("its lengths do not fit".into());
    }
    if opcode != op::CHUNK {
        let record = mcap::parse_record(opcode, body).map_err(|e| describe(&e))?;
        return Ok(vec![record.into_owned()]);
    }
    if let Record::Chunk { header, .. } =
        mcap::parse_record(opcode, body).map_err(|e| describe(&e))?
    {
        if header.uncompressed_size > RECORD_LIMIT {
            return Err("its uncompressed size is wrong".into());
        }
    }
    // MCAP's linear reader checks the CRC of the whole chunk before it parses any record in it
    // (garbage that decompresses must never be parsed: its lengths are arbitrary).
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_prevalidate_chunk_crcs(true)
            .with_record_length_limit(RECORD_LIMIT as usize),
    );
    let mut input: &[u8] = &[];
    let mut head = [0u8; RECORD_HEAD as usize];
    head[0] = opcode;
    head[1..].copy_from_slice(&(body.len() as u64).to_le_bytes());
    let mut parts = [&head[..], body].into_iter();
    let mut records = Vec::new();
    while let Some(event) = reader.next_event() {
        match event.map_err(|e| describe(&e))? {
            LinearReadEvent::ReadRequest(n) => {
                if input.is_empty() {
                    match parts.next() {
                        Some(p) => input = p,
                        // The whole chunk was read: its records are out.
                        None => break,
                    }
                }
                let take = n.min(input.len());
                reader.insert(take).copy_from_slice(&input[..take]);
                reader.notify_read(take);
                input = &input[take..];
            }
            LinearReadEvent::Record { data, opcode } => {
                let r = mcap::parse_record(opcode, data).map_err(|e| describe(&e))?;
                records.push(r.into_owned());
            }
        }
    }
    Ok(records)
}

/// MCAP's parser slices an attachment by the lengths inside it; check they fit first.
fn attachment_fits(body: &[u8]) -> bool {
    let u32_at = |at: usize| -> Option<usize> {
        let b = body.get(at..at + 4)?;
        Some(u32::from_le_bytes(b.try_into().ok()?) as usize)
    };
    let Some(name) = u32_at(16) else { return false };
    let Some(media) = 20usize
        .checked_add(name)
        .and_then(|at| u32_at(at).map(|m| (at + 4, m)))
    else {
        return false;
    };
    let header = media.0.saturating_add(media.1).saturating_add(8);
    header.saturating_add(4) <= body.len()
}

fn describe(e: &mcap::McapError) -> String {
    match e {
        mcap::McapError::BadChunkCrc { .. } | mcap::McapError::BadAttachmentCrc { .. } => {
            "CRC mismatch".into()
        }
        mcap::McapError::UnexpectedEoc => "it ends in the middle of a record".into(),
        mcap::McapError::Parse(_) => "it does not parse".into(),
        other => format!("it does not decompress or parse: {other}"),
    }
}
