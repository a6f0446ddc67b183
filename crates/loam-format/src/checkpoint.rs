//! Checkpoint files: the state a run needs to go on, in one file, so that an interrupted
//! run (or a strength-reduction search) can resume instead of starting again. This module
//! is the file format; what goes into a checkpoint is `restart`'s.
//!
//! Layout, little-endian: the magic `LOAMCKPT`; the format version (u32); the header —
//! loam's version (text), the FNV-1a hash of the scene text (u64), the analysis (text) and
//! the dimension (u32); the number of sections (u64) and each section, in name order: its
//! name (text), its kind (u8: 0 f64, 1 u64, 2 text) and its values (u64 count, then the
//! values); last the checksum of every byte before it (u64): FNV-1a over 8-byte
//! little-endian words, the last one padded with zeros, then over the byte count. Text is a
//! u64 byte count and UTF-8 bytes.
//!
//! Why this format: the state is a few dozen flat arrays of numbers, so named arrays of
//! fixed-width numbers read back bit for bit (the resumed run must be byte-identical), need
//! no dependency beyond the standard library and can be read by any language from this
//! description. HDF5 would add a system library for no gain at this size. The checksum
//! runs a word at a time so that it costs little beside the disk at 10⁶ points; it detects
//! a changed or truncated file (any one word changed always changes it), which is what it
//! is for, and does not defend against tampering. A checkpoint is written to a temporary
//! file and renamed into place, so a run killed while writing one leaves the previous
//! checkpoint whole; one from another scene, another loam or format version, or with a
//! byte changed, is refused as a whole, never half read.

use crate::output::{write_atomic, OutputError};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The checkpoint's name in the output folder.
pub const CHECKPOINT_FILE: &str = "checkpoint.loam";

const MAGIC: &[u8; 8] = b"LOAMCKPT";
/// The version of the layout above; a reader refuses any other.
pub const FORMAT_VERSION: u32 = 1;

const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
const FNV_PRIME: u64 = 0x0100_0000_01b3;

/// What a checkpoint belongs to: a resumed run must match all of it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CheckpointHeader {
    /// loam's version that wrote it (numbers may differ between versions).
    pub loam_version: String,
    /// [`scene_hash`] of the scene text the run was started from.
    pub scene_hash: u64,
    /// The analysis, as `Analysis::name` says it.
    pub analysis: String,
    pub dimension: u32,
}

impl CheckpointHeader {
    /// The header of a run of `scene_text` by this loam.
    pub fn new(scene_text: &str, analysis: &str, dimension: u32) -> Self {
        Self {
            loam_version: env!("CARGO_PKG_VERSION").to_string(),
            scene_hash: scene_hash(scene_text),
            analysis: analysis.to_string(),
            dimension,
        }
    }
}

/// The values of one section.
#[derive(Debug, Clone, PartialEq)]
pub enum Section {
    F64(Vec<f64>),
    U64(Vec<u64>),
    Text(String),
}

/// Why a checkpoint was not read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read the checkpoint {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{} is not a loam checkpoint", path.display())]
    NotACheckpoint { path: PathBuf },
    #[error("{} is damaged ({what}); resume from an earlier checkpoint or run again", path.display())]
    Corrupt { path: PathBuf, what: String },
    #[error("{} has checkpoint format {found}; this loam reads format {FORMAT_VERSION}", path.display())]
    Format { path: PathBuf, found: u32 },
    #[error("{} was written by {what}; resume it with the loam, scene and analysis that wrote it", path.display())]
    Mismatch { path: PathBuf, what: String },
    #[error("the checkpoint has no section `{0}` (written by an incomplete run?)")]
    Missing(String),
    #[error("the checkpoint's section `{0}` holds another kind of value")]
    Kind(String),
    #[error("the checkpoint's section `{section}` does not fit this run: {what}")]
    Section { section: String, what: String },
    #[error("the checkpoint's state does not fit this run: {0}")]
    State(String),
}

/// A checkpoint in memory: its header and its named sections (kept in name order, so the
/// same state always writes the same bytes).
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    pub header: CheckpointHeader,
    sections: BTreeMap<String, Section>,
}

/// FNV-1a, 64 bits, of the scene text: the scene's identity in a checkpoint.
pub fn scene_hash(text: &str) -> u64 {
    fnv1a(text.as_bytes())
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(FNV_OFFSET, |h, &b| (h ^ b as u64).wrapping_mul(FNV_PRIME))
}

/// The file's checksum, fed in pieces of any length: FNV-1a over 8-byte words (the module
/// docs).
#[derive(Debug, Clone)]
struct Checksum {
    hash: u64,
    pending: [u8; 8],
    pending_len: usize,
    bytes: u64,
}

impl Checksum {
    fn new() -> Self {
        Self { hash: FNV_OFFSET, pending: [0; 8], pending_len: 0, bytes: 0 }
    }

    fn word(&mut self, w: [u8; 8]) {
        self.hash = (self.hash ^ u64::from_le_bytes(w)).wrapping_mul(FNV_PRIME);
    }

    fn update(&mut self, mut bytes: &[u8]) {
        self.bytes += bytes.len() as u64;
        if self.pending_len > 0 {
            let n = (8 - self.pending_len).min(bytes.len());
            self.pending[self.pending_len..self.pending_len + n].copy_from_slice(&bytes[..n]);
            self.pending_len += n;
            bytes = &bytes[n..];
            if self.pending_len < 8 {
                return;
            }
            self.word(self.pending);
            self.pending_len = 0;
        }
        let mut words = bytes.chunks_exact(8);
        for w in &mut words {
            self.word(w.try_into().expect("8 bytes"));
        }
        let rest = words.remainder();
        self.pending[..rest.len()].copy_from_slice(rest);
        self.pending_len = rest.len();
    }

    fn finish(mut self) -> u64 {
        if self.pending_len > 0 {
            self.pending[self.pending_len..].fill(0);
            self.word(self.pending);
        }
        (self.hash ^ self.bytes).wrapping_mul(FNV_PRIME)
    }
}

fn checksum(bytes: &[u8]) -> u64 {
    let mut sum = Checksum::new();
    sum.update(bytes);
    sum.finish()
}

/// A writer that keeps the checksum of what went through it.
struct Summed<'w> {
    out: &'w mut dyn Write,
    sum: Checksum,
}

impl Summed<'_> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.sum.update(bytes);
        self.out.write_all(bytes)
    }

    fn text(&mut self, text: &str) -> std::io::Result<()> {
        self.put(&(text.len() as u64).to_le_bytes())?;
        self.put(text.as_bytes())
    }

    /// A section's kind, count and values, converted a block at a time.
    fn numbers<T: Copy>(&mut self, kind: u8, values: &[T], bytes: fn(T) -> [u8; 8]) -> std::io::Result<()> {
        self.put(&[kind])?;
        self.put(&(values.len() as u64).to_le_bytes())?;
        let mut block = Vec::with_capacity(8 * 4096);
        for chunk in values.chunks(4096) {
            block.clear();
            block.extend(chunk.iter().flat_map(|&v| bytes(v)));
            self.put(&block)?;
        }
        Ok(())
    }
}

impl Checkpoint {
    pub fn new(header: CheckpointHeader) -> Self {
        Self { header, sections: BTreeMap::new() }
    }

    pub fn put(&mut self, name: &str, section: Section) {
        self.sections.insert(name.to_string(), section);
    }

    fn get(&self, name: &str) -> Result<&Section, CheckpointError> {
        self.sections.get(name).ok_or_else(|| CheckpointError::Missing(name.to_string()))
    }

    pub fn f64s(&self, name: &str) -> Result<&[f64], CheckpointError> {
        match self.get(name)? {
            Section::F64(v) => Ok(v),
            _ => Err(CheckpointError::Kind(name.to_string())),
        }
    }

    pub fn u64s(&self, name: &str) -> Result<&[u64], CheckpointError> {
        match self.get(name)? {
            Section::U64(v) => Ok(v),
            _ => Err(CheckpointError::Kind(name.to_string())),
        }
    }

    pub fn text(&self, name: &str) -> Result<&str, CheckpointError> {
        match self.get(name)? {
            Section::Text(t) => Ok(t),
            _ => Err(CheckpointError::Kind(name.to_string())),
        }
    }

    /// The file's bytes, checksum included.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = Vec::new();
        self.write_to(&mut bytes).expect("writing to memory does not fail");
        bytes
    }

    /// Stream the file to `out`, the checksum last.
    fn write_to(&self, out: &mut dyn Write) -> std::io::Result<()> {
        let mut w = Summed { out, sum: Checksum::new() };
        w.put(MAGIC)?;
        w.put(&FORMAT_VERSION.to_le_bytes())?;
        w.text(&self.header.loam_version)?;
        w.put(&self.header.scene_hash.to_le_bytes())?;
        w.text(&self.header.analysis)?;
        w.put(&self.header.dimension.to_le_bytes())?;
        w.put(&(self.sections.len() as u64).to_le_bytes())?;
        for (name, section) in &self.sections {
            w.text(name)?;
            match section {
                Section::F64(v) => w.numbers(0, v, f64::to_le_bytes)?,
                Section::U64(v) => w.numbers(1, v, u64::to_le_bytes)?,
                Section::Text(t) => {
                    w.put(&[2])?;
                    w.text(t)?;
                }
            }
        }
        let sum = w.sum.finish();
        w.out.write_all(&sum.to_le_bytes())
    }

    /// Write the checkpoint to `path` atomically (a temporary file, synced, renamed into
    /// place); returns its size in bytes.
    pub fn write(&self, path: &Path) -> Result<u64, OutputError> {
        write_atomic(path, |w: &mut dyn Write| self.write_to(w))?;
        std::fs::metadata(path).map(|m| m.len()).map_err(|source| OutputError::Io { path: path.to_owned(), source })
    }

    /// Read the checkpoint at `path`, refusing it whole unless it is intact, of this
    /// format, and written for `expected` (the same loam, scene, analysis and dimension).
    pub fn read(path: &Path, expected: &CheckpointHeader) -> Result<Self, CheckpointError> {
        let checkpoint = Self::load(path)?;
        checkpoint.verify(path, expected)?;
        Ok(checkpoint)
    }

    /// Read the checkpoint at `path`, refusing it whole unless it is intact and of this
    /// format; whose it is, [`Checkpoint::verify`] says.
    pub fn load(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io { path: path.to_owned(), source })?;
        Self::from_bytes(&bytes).map_err(|e| e.at(path))
    }

    /// Refuse a checkpoint (read from `path`) not written for `expected`: another scene
    /// text, another loam, another analysis or dimension.
    pub fn verify(&self, path: &Path, expected: &CheckpointHeader) -> Result<(), CheckpointError> {
        let h = &self.header;
        let what = if h.scene_hash != expected.scene_hash {
            Some("another scene file (or this one since changed)".to_string())
        } else if h.loam_version != expected.loam_version {
            Some(format!("loam {} (this is loam {})", h.loam_version, expected.loam_version))
        } else if (&h.analysis, h.dimension) != (&expected.analysis, expected.dimension) {
            Some(format!("a {}D {} analysis", h.dimension, h.analysis))
        } else {
            None
        };
        match what {
            Some(what) => Err(CheckpointError::Mismatch { path: path.to_owned(), what }),
            None => Ok(()),
        }
    }

    /// Parse a checkpoint's bytes: the magic, the checksum, the format, then the contents,
    /// every length checked against what is left.
    fn from_bytes(bytes: &[u8]) -> Result<Self, ReadError> {
        if bytes.len() < MAGIC.len() + 12 || &bytes[..MAGIC.len()] != MAGIC {
            return Err(ReadError::NotACheckpoint);
        }
        let (body, sum) = bytes.split_at(bytes.len() - 8);
        if checksum(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
            return Err(ReadError::Corrupt("its checksum does not match its contents".into()));
        }
        let mut r = Reader { bytes: body, at: MAGIC.len() };
        let format = r.u32()?;
        if format != FORMAT_VERSION {
            return Err(ReadError::Format(format));
        }
        let header = CheckpointHeader {
            loam_version: r.text()?,
            scene_hash: r.u64()?,
            analysis: r.text()?,
            dimension: r.u32()?,
        };
        let mut checkpoint = Self::new(header);
        for _ in 0..r.u64()? {
            let name = r.text()?;
            let section = r.section()?;
            checkpoint.sections.insert(name, section);
        }
        if r.at != body.len() {
            return Err(ReadError::Corrupt(format!("{} bytes after the last section", body.len() - r.at)));
        }
        Ok(checkpoint)
    }
}

/// A failure of [`Checkpoint::from_bytes`], before it knows the file's path.
enum ReadError {
    NotACheckpoint,
    Corrupt(String),
    Format(u32),
}

impl ReadError {
    fn at(self, path: &Path) -> CheckpointError {
        let path = path.to_owned();
        match self {
            ReadError::NotACheckpoint => CheckpointError::NotACheckpoint { path },
            ReadError::Corrupt(what) => CheckpointError::Corrupt { path, what },
            ReadError::Format(found) => CheckpointError::Format { path, found },
        }
    }
}

/// A cursor over a checkpoint's body that never reads past its end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], ReadError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| ReadError::Corrupt(format!("it ends inside a value at byte {}", self.at)))?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn u32(&mut self) -> Result<u32, ReadError> {
        Ok(u32::from_le_bytes(self.take(4)?.try_into().expect("4 bytes")))
    }

    fn u64(&mut self) -> Result<u64, ReadError> {
        Ok(u64::from_le_bytes(self.take(8)?.try_into().expect("8 bytes")))
    }

    fn len(&mut self, width: usize) -> Result<usize, ReadError> {
        let n = self.u64()?;
        usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(width))
            .ok_or_else(|| ReadError::Corrupt(format!("a length of {n}")))
    }

    fn text(&mut self) -> Result<String, ReadError> {
        let n = self.len(1)?;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| ReadError::Corrupt("a name that is not UTF-8".into()))
    }

    fn section(&mut self) -> Result<Section, ReadError> {
        let kind = self.take(1)?[0];
        Ok(match kind {
            0 => {
                let n = self.len(8)?;
                Section::F64(self.take(n)?.chunks(8).map(|c| f64::from_le_bytes(c.try_into().expect("8"))).collect())
            }
            1 => {
                let n = self.len(8)?;
                Section::U64(self.take(n)?.chunks(8).map(|c| u64::from_le_bytes(c.try_into().expect("8"))).collect())
            }
            2 => Section::Text(self.text()?),
            k => return Err(ReadError::Corrupt(format!("a section of unknown kind {k}"))),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Checkpoint {
        let mut c = Checkpoint::new(CheckpointHeader::new("Scene(...)", "quasi-static", 2));
        c.put("points.position", Section::F64(vec![0.1, -2.5e-300, f64::MAX, -0.0]));
        c.put("run.step", Section::U64(vec![17]));
        c.put("run.solver", Section::Text("sparse Cholesky".into()));
        c
    }

    /// What is written reads back bit for bit (−0.0 and the extremes included), through a
    /// file written atomically.
    #[test]
    fn a_checkpoint_reads_back_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.bin");
        let c = sample();
        c.write(&path).unwrap();
        let back = Checkpoint::read(&path, &c.header).unwrap();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(back.f64s("points.position").unwrap()), bits(c.f64s("points.position").unwrap()));
        assert_eq!(
            (back.u64s("run.step").unwrap(), back.text("run.solver").unwrap()),
            (&[17u64][..], "sparse Cholesky")
        );
        assert_eq!(back, c);
        assert!(matches!(back.f64s("run.step"), Err(CheckpointError::Kind(_))));
        assert!(matches!(back.f64s("points.velocity"), Err(CheckpointError::Missing(_))));
    }

    /// Every byte changed, and every truncation, is refused whole, never half read; so is
    /// a file that is not a checkpoint, another format, another scene or another loam.
    #[test]
    fn a_damaged_or_foreign_checkpoint_is_refused() {
        let c = sample();
        let bytes = c.to_bytes();
        for k in 0..bytes.len() {
            let mut bad = bytes.clone();
            bad[k] ^= 0x10;
            assert!(Checkpoint::from_bytes(&bad).is_err(), "byte {k} changed was accepted");
            assert!(Checkpoint::from_bytes(&bytes[..k]).is_err(), "truncation to {k} bytes was accepted");
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("checkpoint.bin");
        std::fs::write(&path, b"points.pvd is not a checkpoint").unwrap();
        assert!(matches!(Checkpoint::read(&path, &c.header), Err(CheckpointError::NotACheckpoint { .. })));
        let mut other_format = bytes.clone();
        other_format[8..12].copy_from_slice(&2u32.to_le_bytes());
        let n = other_format.len() - 8;
        let sum = checksum(&other_format[..n]);
        other_format[n..].copy_from_slice(&sum.to_le_bytes());
        assert!(matches!(Checkpoint::from_bytes(&other_format), Err(ReadError::Format(2))));
        c.write(&path).unwrap();
        let other_scene = CheckpointHeader::new("Scene(changed)", "quasi-static", 2);
        let e = Checkpoint::read(&path, &other_scene).unwrap_err();
        assert!(e.to_string().contains("another scene file"), "{e}");
        let other_loam = CheckpointHeader { loam_version: "0.0.1".into(), ..c.header.clone() };
        let e = Checkpoint::read(&path, &other_loam).unwrap_err();
        assert!(e.to_string().contains("this is loam 0.0.1"), "{e}");
    }

    /// The checksum fed in pieces of any length is the checksum of the whole, and changes
    /// with any one byte and with trailing zeros (the byte count is in it).
    #[test]
    fn the_checksum_does_not_depend_on_how_it_is_fed() {
        let bytes: Vec<u8> = (0..1000u32).map(|k| (k.wrapping_mul(2_654_435_761) >> 24) as u8).collect();
        let whole = checksum(&bytes);
        for piece in [1, 3, 7, 8, 9, 64, 999] {
            let mut sum = Checksum::new();
            bytes.chunks(piece).for_each(|c| sum.update(c));
            assert_eq!(sum.finish(), whole, "pieces of {piece}");
        }
        let mut padded = bytes.clone();
        padded.push(0);
        assert_ne!(checksum(&padded), whole);
    }

    /// The FNV-1a reference values (Fowler, Noll, Vo: the published test vectors).
    #[test]
    fn fnv1a_matches_its_reference_values() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
