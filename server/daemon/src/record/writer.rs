//! MCAP files in a folder, rotated by size and time: `shift-{run}-{index}.mcap`, zstd chunks, the `ros2`
//! profile. A file is written as `….mcap.part` and renamed once `finish()` wrote its summary, so a finished
//! name is always a complete file (a crash leaves a `.part` that MCAP tools still read up to its last chunk).
//! Schemas and channels are declared per file, on first use, so every file stands on its own.

use std::collections::HashMap;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use crate::error::{Context, Result};
use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions, Writer};

use super::channels::Kind;

/// Where and how big.
#[derive(Debug, Clone)]
pub struct FileSettings {
    /// Output folder (created if missing).
    pub dir: PathBuf,
    /// Daemon run (start time, ms since the Unix epoch): part of every file name.
    pub run: u64,
    /// Rotate at this many bytes (0 = never by size).
    pub max_file_bytes: u64,
    /// Rotate after this long (zero = never by time).
    pub max_file_age: Duration,
    /// Uncompressed bytes per chunk.
    pub chunk_bytes: u64,
}

/// A `Write + Seek` that remembers how far the file reaches, bytes.
struct Counting<W> {
    inner: W,
    pos: u64,
    len: Arc<AtomicU64>,
}

impl<W: Write> Write for Counting<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.pos += n as u64;
        self.len.fetch_max(self.pos, Ordering::Relaxed);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

impl<W: Seek> Seek for Counting<W> {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.pos = self.inner.seek(to)?;
        self.len.fetch_max(self.pos, Ordering::Relaxed);
        Ok(self.pos)
    }
}

struct OpenFile {
    writer: Writer<Counting<BufWriter<File>>>,
    /// Bytes the file reaches on disk.
    len: Arc<AtomicU64>,
    part: PathBuf,
    path: PathBuf,
    schemas: HashMap<Kind, u16>,
    channels: HashMap<(Kind, String), u16>,
    opened: Instant,
    /// Message bytes since the last chunk was cut (an upper bound of what is not on disk yet).
    pending: u64,
    messages: u64,
}

/// The writer of one daemon run's files.
pub struct RotatingWriter {
    settings: FileSettings,
    file: Option<OpenFile>,
    next_index: u32,
    /// Written at the start of every file (the engine's sizes): kind, topic, payload.
    preamble: Vec<(Kind, String, Vec<u8>)>,
    finished: Vec<PathBuf>,
}

impl RotatingWriter {
    /// No file is created until the first message.
    pub fn new(settings: FileSettings) -> Self {
        Self {
            settings,
            file: None,
            next_index: 0,
            preamble: Vec::new(),
            finished: Vec::new(),
        }
    }

    /// A message that opens every file (logged at the file's first message time).
    pub fn set_preamble(&mut self, kind: Kind, topic: &str, data: Vec<u8>) {
        self.preamble.push((kind, topic.to_owned(), data));
    }

    /// Files finished so far.
    pub fn finished(&self) -> &[PathBuf] {
        &self.finished
    }

    fn open(&mut self) -> Result<()> {
        let s = &self.settings;
        std::fs::create_dir_all(&s.dir).with_context(|| format!("creating {}", s.dir.display()))?;
        let path = s.dir.join(format!("shift-{}-{:04}.mcap", s.run, self.next_index));
        self.next_index += 1;
        let part = path.with_extension("mcap.part");
        let f = File::create(&part).with_context(|| format!("creating {}", part.display()))?;
        let len = Arc::new(AtomicU64::new(0));
        let out = Counting {
            inner: BufWriter::new(f),
            pos: 0,
            len: len.clone(),
        };
        let writer = WriteOptions::new()
            .compression(Some(Compression::Zstd))
            .profile("ros2")
            .library(concat!("shiftd ", env!("CARGO_PKG_VERSION")))
            .chunk_size(Some(s.chunk_bytes.max(1024)))
            .create(out)
            .with_context(|| format!("starting {}", part.display()))?;
        tracing::info!(file = %path.display(), "recording to a new MCAP file");
        self.file = Some(OpenFile {
            writer,
            len,
            part,
            path,
            schemas: HashMap::new(),
            channels: HashMap::new(),
            opened: Instant::now(),
            pending: 0,
            messages: 0,
        });
        Ok(())
    }

    fn due(&self, f: &OpenFile) -> bool {
        let s = &self.settings;
        let bytes = f.len.load(Ordering::Relaxed) + f.pending;
        (s.max_file_bytes > 0 && bytes >= s.max_file_bytes)
            || (!s.max_file_age.is_zero() && f.opened.elapsed() >= s.max_file_age)
    }

    /// Writes one message, opening or rotating the file first when due.
    pub fn write(&mut self, kind: Kind, topic: &str, log_time_ns: u64, data: &[u8]) -> Result<()> {
        if self.file.as_ref().is_some_and(|f| f.messages > 0 && self.due(f)) {
            self.finish()?;
        }
        if self.file.is_none() {
            self.open()?;
            for (k, t, d) in std::mem::take(&mut self.preamble) {
                let r = self.put(k, &t, log_time_ns, &d);
                self.preamble.push((k, t, d));
                r?;
            }
        }
        self.put(kind, topic, log_time_ns, data)
    }

    fn put(&mut self, kind: Kind, topic: &str, log_time_ns: u64, data: &[u8]) -> Result<()> {
        let chunk = self.settings.chunk_bytes.max(1024);
        let Some(f) = self.file.as_mut() else {
            crate::bail!("no open recording file");
        };
        let schema_id = match f.schemas.get(&kind) {
            Some(&id) => id,
            None => {
                let s = kind.schema();
                let id = f.writer.add_schema(s.name, s.encoding, s.text.as_bytes())?;
                f.schemas.insert(kind, id);
                id
            }
        };
        let key = (kind, topic.to_owned());
        let channel_id = match f.channels.get(&key) {
            Some(&id) => id,
            None => {
                let id = f
                    .writer
                    .add_channel(schema_id, topic, kind.message_encoding(), &kind.metadata())?;
                f.channels.insert(key, id);
                id
            }
        };
        f.writer.write_to_known_channel(
            &MessageHeader {
                channel_id,
                sequence: f.messages as u32,
                log_time: log_time_ns,
                publish_time: log_time_ns,
            },
            data,
        )?;
        f.messages += 1;
        f.pending += data.len() as u64 + 32;
        if f.pending >= chunk {
            // The writer cut a chunk (or is about to): what is on disk is counted by `Counting`.
            f.pending = f.pending.saturating_sub(chunk);
        }
        Ok(())
    }

    /// Rotates by time when the open file is old enough (called when idle, too).
    pub fn tick(&mut self) -> Result<()> {
        if self.file.as_ref().is_some_and(|f| self.due(f)) {
            self.finish()?;
        }
        Ok(())
    }

    /// Ends the open chunk and flushes it to disk: a crash after this loses nothing written before.
    pub fn flush(&mut self) -> Result<()> {
        if let Some(f) = self.file.as_mut() {
            f.writer.flush()?;
            f.pending = 0;
        }
        Ok(())
    }

    /// Finishes the open file (summary, footer), renames it to its final name and returns that name.
    pub fn finish(&mut self) -> Result<Option<PathBuf>> {
        let Some(mut f) = self.file.take() else {
            return Ok(None);
        };
        f.writer
            .finish()
            .with_context(|| format!("finishing {}", f.part.display()))?;
        drop(f.writer);
        std::fs::rename(&f.part, &f.path).with_context(|| format!("renaming {}", f.part.display()))?;
        tracing::info!(file = %f.path.display(), messages = f.messages, "MCAP file finished");
        self.finished.push(f.path.clone());
        Ok(Some(f.path))
    }
}

/// Finished recordings (`*.mcap`) in `dir`, oldest first (names sort by run and index).
pub fn recordings_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("reading {}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
        .collect();
    files.sort();
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read_all(path: &Path) -> Vec<(String, u64, Vec<u8>)> {
        let bytes = std::fs::read(path).expect("file");
        mcap::MessageStream::new(&bytes)
            .expect("mcap")
            .map(|m| {
                let m = m.expect("message");
                (m.channel.topic.clone(), m.log_time, m.data.to_vec())
            })
            .collect()
    }

    #[test]
    fn files_rotate_by_size_and_each_is_complete() {
        let dir = tempfile::tempdir().expect("tmp");
        let mut w = RotatingWriter::new(FileSettings {
            dir: dir.path().join("rec"),
            run: 42,
            max_file_bytes: 16 * 1024,
            max_file_age: Duration::ZERO,
            chunk_bytes: 4 * 1024,
        });
        w.set_preamble(Kind::EngineConfig, "/shift/engine/config", b"{\"run\":42}".to_vec());
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        for i in 0..200u64 {
            // Incompressible payloads (xorshift) so the size limit is reached.
            let data: Vec<u8> = (0..500)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    x as u8
                })
                .collect();
            w.write(Kind::PointCloud2, "shift/default/robots/r1/cloud", i, &data)
                .expect("write");
        }
        w.finish().expect("finish");
        let files = recordings_in(&dir.path().join("rec")).expect("list");
        assert!(files.len() >= 3, "{files:?}");
        assert_eq!(files, w.finished());
        let mut seen = Vec::new();
        for f in &files {
            let name = f.file_name().and_then(|n| n.to_str()).expect("name");
            assert!(name.starts_with("shift-42-"), "{name}");
            let msgs = read_all(f);
            assert_eq!(
                msgs[0].0, "/shift/engine/config",
                "every file starts with the engine config"
            );
            for (topic, t, _) in &msgs[1..] {
                assert_eq!(topic, "shift/default/robots/r1/cloud");
                seen.push(*t);
            }
            let len = std::fs::metadata(f).expect("meta").len();
            assert!(len < 16 * 1024 + 8 * 1024, "{name}: {len} bytes");
        }
        assert_eq!(seen, (0..200).collect::<Vec<_>>(), "every message once, in order");
        let left: Vec<_> = std::fs::read_dir(dir.path().join("rec"))
            .expect("dir")
            .filter_map(|e| e.ok())
            .filter(|e| e.path().to_string_lossy().ends_with(".part"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    #[test]
    fn files_rotate_by_age_when_idle() {
        let dir = tempfile::tempdir().expect("tmp");
        let mut w = RotatingWriter::new(FileSettings {
            dir: dir.path().to_path_buf(),
            run: 1,
            max_file_bytes: 0,
            max_file_age: Duration::from_millis(1),
            chunk_bytes: 1 << 20,
        });
        w.write(Kind::Liveliness, "/shift/liveliness", 1, b"{}").expect("write");
        std::thread::sleep(Duration::from_millis(5));
        w.tick().expect("tick");
        assert_eq!(w.finished().len(), 1, "the old file is finished while idle");
        w.write(Kind::Liveliness, "/shift/liveliness", 2, b"{}").expect("write");
        w.finish().expect("finish");
        assert_eq!(recordings_in(dir.path()).expect("list").len(), 2);
        assert_eq!(w.finish().expect("again"), None);
    }
}
