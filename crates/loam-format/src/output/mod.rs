//! Output writers: VTK XML point clouds (`.vtu`), ParaView collections
//! (`.pvd`) and CSV tables/logs.
//!
//! CSV and PVD files are text; VTU frames are text or compressed binary (`VtuFormat`).
//! Whole-file writes (VTU, PVD, whole CSV tables) go to a temporary file in the
//! destination folder (`tempfile`) which is then renamed over the destination, so a
//! reader never sees a half-written file and a failed write leaves the destination
//! untouched. Append-only CSV logs flush after every row instead.

mod csv;
pub mod plot;
mod pvd;
mod vtu;

pub use csv::{write_csv_table, CsvCell, CsvWriter};
pub use pvd::PvdWriter;
pub use vtu::{write_vtu, VtuFormat};

use std::ffi::{OsStr, OsString};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use tempfile::NamedTempFile;

/// A borrowed view of the point fields to write, struct-of-arrays.
///
/// With `n = positions.len() / dim` points:
/// - `positions`: `n * dim` values, point-major (`x0, y0, [z0], x1, ...`);
/// - `scalars`: one value per point (`n` each);
/// - `vectors`: `dim` components per point (`n * dim` each); padded with
///   zeros to 3 components in VTU output;
/// - `tensors`: symmetric 3x3 tensors, 6 components per point (`n * 6`
///   each) in the order `xx, yy, zz, xy, yz, xz` (the order ParaView expects
///   for 6-component symmetric tensors), also in 2D.
#[derive(Debug, Clone)]
pub struct PointCloud<'a> {
    /// Spatial dimension, 2 or 3.
    pub dim: usize,
    /// Point coordinates, `n * dim` values, point-major.
    pub positions: &'a [f64],
    /// Named per-point scalar fields, `n` values each.
    pub scalars: Vec<(&'a str, &'a [f64])>,
    /// Named per-point vector fields, `n * dim` values each.
    pub vectors: Vec<(&'a str, &'a [f64])>,
    /// Named per-point symmetric tensor fields, `n * 6` values each
    /// (`xx, yy, zz, xy, yz, xz`).
    pub tensors: Vec<(&'a str, &'a [f64])>,
}

impl<'a> PointCloud<'a> {
    /// A cloud with positions only; add fields with the builder methods or
    /// by pushing onto the public vectors.
    pub fn new(dim: usize, positions: &'a [f64]) -> Self {
        Self { dim, positions, scalars: Vec::new(), vectors: Vec::new(), tensors: Vec::new() }
    }

    /// Adds a per-point scalar field.
    pub fn with_scalar(mut self, name: &'a str, values: &'a [f64]) -> Self {
        self.scalars.push((name, values));
        self
    }

    /// Adds a per-point vector field (`dim` components per point).
    pub fn with_vector(mut self, name: &'a str, values: &'a [f64]) -> Self {
        self.vectors.push((name, values));
        self
    }

    /// Adds a per-point symmetric tensor field (6 components per point).
    pub fn with_tensor(mut self, name: &'a str, values: &'a [f64]) -> Self {
        self.tensors.push((name, values));
        self
    }

    /// Number of points (`positions.len() / dim`; 0 for an invalid `dim`).
    pub fn len(&self) -> usize {
        self.positions.len().checked_div(self.dim).unwrap_or(0)
    }

    /// Whether the cloud has no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Checks `dim`, every field's length, and that every value is finite.
    ///
    /// Shapes are checked for all fields before any value is looked at.
    pub fn validate(&self) -> Result<(), OutputError> {
        if self.dim != 2 && self.dim != 3 {
            return Err(OutputError::Dim { found: self.dim });
        }
        let n = self.len();
        let check_len = |field: &str, expected: usize, found: usize| {
            if expected == found {
                Ok(())
            } else {
                Err(OutputError::Shape { field: field.to_owned(), expected, found })
            }
        };
        check_len("positions", n * self.dim, self.positions.len())?;
        for (name, v) in &self.scalars {
            check_len(name, n, v.len())?;
        }
        for (name, v) in &self.vectors {
            check_len(name, n * self.dim, v.len())?;
        }
        for (name, v) in &self.tensors {
            check_len(name, n * 6, v.len())?;
        }

        check_finite("positions", self.positions, self.dim)?;
        for (name, v) in &self.scalars {
            check_finite(name, v, 1)?;
        }
        for (name, v) in &self.vectors {
            check_finite(name, v, self.dim)?;
        }
        for (name, v) in &self.tensors {
            check_finite(name, v, 6)?;
        }
        Ok(())
    }
}

/// Errors from the output writers.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// An I/O operation on `path` failed.
    #[error("I/O error on {}", path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The underlying error.
        source: io::Error,
    },
    /// A field (or CSV row) has the wrong number of values.
    #[error("field `{field}` has {found} values, expected {expected}")]
    Shape {
        /// The field, or `"row"`/`"columns"` for CSV arity errors.
        field: String,
        /// The number of values required.
        expected: usize,
        /// The number of values given.
        found: usize,
    },
    /// A field holds NaN or an infinity; it is never written silently.
    #[error("field `{field}` is not finite (NaN or infinite) at point {point}")]
    NonFinite {
        /// The offending field.
        field: String,
        /// Index of the offending point (or entry, e.g. PVD data set).
        point: usize,
    },
    /// A quantity of the run (an energy, a momentum) overflowed: the run has gone unstable
    /// and stops, the rows before kept.
    #[error("{what} is not finite at t = {time:e}: the run has gone unstable (a velocity or an energy overflowed) and stops here; the outputs so far are kept")]
    Unstable {
        /// The quantity, as its column is named.
        what: String,
        /// The time (or load factor) of the row.
        time: f64,
    },
    /// A file a resumed run goes on writing is not as the checkpoint left it.
    #[error("cannot resume writing {}: {what}; the folder does not hold the outputs of the checkpoint's run", path.display())]
    Resume {
        /// The file.
        path: PathBuf,
        /// What differs.
        what: String,
    },
    /// `PointCloud::dim` is neither 2 nor 3.
    #[error("point cloud dimension must be 2 or 3, found {found}")]
    Dim {
        /// The dimension given.
        found: usize,
    },
}

fn check_finite(field: &str, values: &[f64], comps: usize) -> Result<(), OutputError> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(OutputError::NonFinite { field: field.to_owned(), point: i / comps.max(1) }),
    }
}

pub(crate) fn io_err(path: &Path) -> impl FnOnce(io::Error) -> OutputError + '_ {
    move |source| OutputError::Io { path: path.to_path_buf(), source }
}

/// Formats a finite `f64` so that it parses back to the same value.
///
/// Uses plain decimal (`Display`) for ordinary magnitudes, and exponent form
/// (`LowerExp`, e.g. `1.5e-12`) for very small or very large ones, where
/// `Display` would print hundreds of digits. Both are shortest round-trip
/// representations understood by C/C++ stream parsers, Python and numpy.
/// Non-finite values print as Rust's `NaN`, `inf`, `-inf`.
pub(crate) fn fmt_f64(x: f64) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Writes a file atomically: `fill` writes into a temporary file in the same
/// folder as `path`, which is synced and then renamed over `path`, so a reader
/// sees the old file or the whole new one. On error the temporary file is
/// removed and `path` is untouched.
pub(crate) fn write_atomic<F>(path: &Path, fill: F) -> Result<(), OutputError>
where
    F: FnOnce(&mut dyn Write) -> io::Result<()>,
{
    let file_name = path.file_name().ok_or_else(|| OutputError::Io {
        path: path.to_path_buf(),
        source: io::Error::new(io::ErrorKind::InvalidInput, "path has no file name"),
    })?;
    // The same folder, so that the rename stays on one file system and is atomic.
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let result = (|| -> io::Result<()> {
        // Dropped on any error below, the temporary file deletes itself.
        let mut tmp = temp_file_in(dir, file_name)?;
        let mut w = BufWriter::new(tmp.as_file_mut());
        fill(&mut w)?;
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        tmp.persist(path).map_err(|e| e.error)?;
        Ok(())
    })();
    result.map_err(io_err(path))
}

/// A temporary file in `dir` named after the file it will replace (`.name.XXXXXX.tmp`,
/// so that one left by a killed run says whose it is), created with the permissions
/// `File::create` gives: tempfile's default, owner-only, would carry over to the output.
fn temp_file_in(dir: &Path, file_name: &OsStr) -> io::Result<NamedTempFile> {
    let mut prefix = OsString::from(".");
    prefix.push(file_name);
    prefix.push(".");
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    builder.tempfile_in(dir)
}

/// Escapes a string for use inside an XML attribute value or text node.
pub(crate) fn xml_escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn fmt_f64_round_trips() {
        for &x in &[
            0.0,
            -0.0,
            1.0,
            -2.5,
            0.1,
            1.0 / 3.0,
            1e-5,
            9.99e-6,
            1e15,
            1e16,
            1e-300,
            1.7e308,
            f64::MIN_POSITIVE,
            5e-324,
            123456.789,
        ] {
            let s = fmt_f64(x);
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{x} -> {s}");
            assert!(s.len() < 30, "{s}");
        }
        assert_eq!(fmt_f64(0.5), "0.5");
        assert_eq!(fmt_f64(1e-7), "1e-7");
    }

    #[test]
    fn xml_escape_special_chars() {
        assert_eq!(xml_escape(r#"a<b>&"c'"#), "a&lt;b&gt;&amp;&quot;c&apos;");
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("x.txt");
        write_atomic(&p, |w| w.write_all(b"one")).unwrap();
        write_atomic(&p, |w| w.write_all(b"two")).unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "two");
        // A failing writer leaves the old file intact and no temp file.
        let err = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(io::Error::other("boom"))
        })
        .unwrap_err();
        assert!(matches!(err, OutputError::Io { .. }));
        assert_eq!(fs::read_to_string(&p).unwrap(), "two");
        let names: Vec<_> = fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    /// An output gets the permissions of any file the user creates, not the
    /// owner-only ones of a temporary file.
    #[cfg(unix)]
    #[test]
    fn atomic_write_keeps_the_usual_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let mode = |p: &Path| fs::metadata(p).unwrap().permissions().mode();
        let (atomic, plain) = (dir.path().join("a.txt"), dir.path().join("b.txt"));
        write_atomic(&atomic, |w| w.write_all(b"a")).unwrap();
        fs::File::create(&plain).unwrap();
        assert_eq!(mode(&atomic), mode(&plain));
    }

    #[test]
    fn a_path_without_a_file_name_is_refused() {
        let err = write_atomic(Path::new("/"), |w| w.write_all(b"x")).unwrap_err();
        match err {
            OutputError::Io { path, source } => {
                assert_eq!(path, Path::new("/"));
                assert_eq!(source.kind(), io::ErrorKind::InvalidInput);
            }
            e => panic!("{e:?}"),
        }
    }

    #[test]
    fn missing_folder_is_io_error_naming_path() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nope").join("x.txt");
        let err = write_atomic(&p, |w| w.write_all(b"x")).unwrap_err();
        match err {
            OutputError::Io { path, .. } => assert_eq!(path, p),
            e => panic!("{e:?}"),
        }
    }
}
