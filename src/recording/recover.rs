//! Rewriting a recording record by record: `critterbox recover` makes a complete, indexed file
//! from a cut-off or damaged one (the good chunks' messages, every readable attachment and
//! metadata record; damaged chunks are left out and named), and tests use the same copy to
//! alter one message.

use super::error::RecordingError;
use super::reader::{read_items, Flow, Item};
use super::schema;
use mcap::records::{MessageHeader, Metadata};
use mcap::{Attachment, WriteOptions};
use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

/// What a rewrite kept.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rewritten {
    /// Messages written.
    pub messages: u64,
    /// Attachments written.
    pub attachments: u64,
    /// Metadata records written (the added `critterbox.recovered` one not counted).
    pub metadata: u64,
    /// The last step of a hash message kept.
    pub last_step: Option<u64>,
    /// Why the source's readable part ended early, if it did.
    pub truncated: Option<String>,
    /// True when the source had its end record.
    pub had_end: bool,
    /// The source's damaged stretches, left out, with the steps they took.
    pub gaps: Vec<super::reader::Gap>,
}

impl Rewritten {
    /// True when the source was cut off or damaged (so the copy lacks something).
    pub fn lost_data(&self) -> bool {
        self.truncated.is_some() || !self.gaps.is_empty()
    }
}

/// Copies `src` to `dst`, passing each message through `edit(topic, data)` (return `None` to
/// keep it as is). When `src` was cut off or damaged, a `critterbox.recovered` metadata record
/// says so.
pub fn rewrite(
    src: &Path,
    dst: &Path,
    mut edit: impl FnMut(&str, &[u8]) -> Option<Vec<u8>>,
) -> Result<Rewritten, RecordingError> {
    if src.canonicalize().ok() == dst.canonicalize().ok() && dst.exists() {
        return Err(RecordingError::WouldOverwrite {
            path: dst.to_path_buf(),
        });
    }
    // Check it is a recording before creating anything.
    let source = super::reader::Recording::open(src)?;
    let file = File::create(dst).map_err(|error| RecordingError::CannotCreate {
        path: dst.to_path_buf(),
        error,
    })?;
    let mut w = WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_threads(0)
        .profile("critterbox")
        .library(format!("critterbox {}", env!("CARGO_PKG_VERSION")))
        .create(BufWriter::new(file))?;
    let mut channels: BTreeMap<u16, u16> = BTreeMap::new();
    let mut out = Rewritten::default();
    let end = read_items(src, |item| {
        match item {
            Item::Damaged(_) => {}
            Item::Channel {
                id,
                topic,
                schema,
                schema_encoding,
                schema_data,
                message_encoding,
            } => {
                let schema_id = if schema.is_empty() {
                    0
                } else {
                    w.add_schema(schema, schema_encoding, schema_data)?
                };
                let new = w.add_channel(schema_id, topic, message_encoding, &BTreeMap::new())?;
                channels.insert(id, new);
            }
            Item::Metadata { name, map } => {
                out.metadata += 1;
                out.had_end |= name == schema::END;
                w.write_metadata(&Metadata {
                    name: name.to_string(),
                    metadata: map.clone(),
                })?;
            }
            Item::Attachment {
                name,
                media_type,
                data,
                log_time,
                create_time,
            } => {
                out.attachments += 1;
                w.attach(&Attachment {
                    log_time,
                    create_time,
                    name: name.to_string(),
                    media_type: media_type.to_string(),
                    data: Cow::Borrowed(data),
                })?;
            }
            Item::Message {
                topic,
                channel,
                sequence,
                log_time,
                publish_time,
                data,
            } => {
                let Some(&channel_id) = channels.get(&channel) else {
                    return Ok(Flow::Continue);
                };
                if topic == schema::HASH {
                    #[derive(serde::Deserialize)]
                    struct Step {
                        step: u64,
                    }
                    if let Ok(s) = serde_json::from_slice::<Step>(data) {
                        out.last_step = Some(s.step);
                    }
                }
                let edited = edit(topic, data);
                out.messages += 1;
                w.write_to_known_channel(
                    &MessageHeader {
                        channel_id,
                        sequence,
                        log_time,
                        publish_time,
                    },
                    edited.as_deref().unwrap_or(data),
                )?;
            }
        }
        Ok(Flow::Continue)
    })?;
    out.truncated = end.truncated;
    out.gaps = source.gaps;
    if out.lost_data() {
        let mut reasons: Vec<String> = out.gaps.iter().map(|g| g.to_string()).collect();
        reasons.extend(out.truncated.clone());
        w.write_metadata(&Metadata {
            name: schema::RECOVERED.into(),
            metadata: BTreeMap::from([
                ("from".to_string(), src.display().to_string()),
                ("reason".to_string(), reasons.join("; ")),
                (
                    "last_step".to_string(),
                    out.last_step.map_or(String::new(), |s| s.to_string()),
                ),
                ("messages".to_string(), out.messages.to_string()),
            ]),
        })?;
    }
    w.finish()?;
    Ok(out)
}
