//! ParaView data collection (`.pvd`) writer for time series of `.vtu` files.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::{fmt_f64, write_atomic, xml_escape, OutputError};

/// A ParaView collection file listing one data file per time step.
///
/// The whole `.pvd` file is rewritten atomically (temporary file + rename)
/// on [`PvdWriter::create`] and after every [`PvdWriter::add`], so the
/// collection on disk is always complete and openable, even if the run
/// dies part-way.
#[derive(Debug, Clone)]
pub struct PvdWriter {
    path: PathBuf,
    entries: Vec<(f64, String)>,
}

impl PvdWriter {
    /// Creates (or truncates) the collection at `path`, writing an empty but
    /// valid collection immediately.
    pub fn create(path: impl AsRef<Path>) -> Result<Self, OutputError> {
        let w = Self { path: path.as_ref().to_path_buf(), entries: Vec::new() };
        w.flush()?;
        Ok(w)
    }

    /// Go on with the collection at `path` as a checkpoint left it: `entries` (time, file)
    /// are written at once, any data set listed after them dropped.
    pub fn resume(path: impl AsRef<Path>, entries: Vec<(f64, String)>) -> Result<Self, OutputError> {
        let w = Self { path: path.as_ref().to_path_buf(), entries };
        w.flush()?;
        Ok(w)
    }

    /// The data sets listed: (time, file).
    pub fn entries(&self) -> &[(f64, String)] {
        &self.entries
    }

    /// Appends a data set at `time`, referring to `vtu_file_name_relative`
    /// (a path relative to the folder of the `.pvd` file), then rewrites the
    /// collection. A non-finite `time` is refused and nothing changes.
    pub fn add(&mut self, time: f64, vtu_file_name_relative: &str) -> Result<(), OutputError> {
        if !time.is_finite() {
            return Err(OutputError::NonFinite { field: "time".to_owned(), point: self.entries.len() });
        }
        self.entries.push((time, vtu_file_name_relative.to_owned()));
        if let Err(e) = self.flush() {
            self.entries.pop();
            return Err(e);
        }
        Ok(())
    }

    /// The path of the `.pvd` file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of data sets in the collection.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the collection is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    fn flush(&self) -> Result<(), OutputError> {
        write_atomic(&self.path, |w: &mut dyn Write| {
            writeln!(w, r#"<?xml version="1.0"?>"#)?;
            writeln!(w, r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#)?;
            writeln!(w, "  <Collection>")?;
            for (t, file) in &self.entries {
                writeln!(
                    w,
                    r#"    <DataSet timestep="{}" group="" part="0" file="{}"/>"#,
                    fmt_f64(*t),
                    xml_escape(file)
                )?;
            }
            writeln!(w, "  </Collection>")?;
            writeln!(w, "</VTKFile>")
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    /// Minimal well-formedness check for the collection file: prolog, matched
    /// root and Collection elements, and one self-closed DataSet line per
    /// entry, all inside the Collection.
    fn check_pvd(text: &str, expected_sets: usize) {
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        assert_eq!(lines.first(), Some(&r#"<?xml version="1.0"?>"#));
        assert!(lines[1].starts_with(r#"<VTKFile type="Collection""#));
        assert_eq!(lines[2], "<Collection>");
        let sets = &lines[3..lines.len() - 2];
        assert_eq!(sets.len(), expected_sets);
        for l in sets {
            assert!(l.starts_with("<DataSet ") && l.ends_with("/>"), "{l}");
            assert_eq!(l.matches('"').count() % 2, 0, "{l}");
        }
        assert_eq!(lines[lines.len() - 2], "</Collection>");
        assert_eq!(lines[lines.len() - 1], "</VTKFile>");
        assert_eq!(text.lines().filter(|l| l.contains("<DataSet")).count(), expected_sets);
    }

    #[test]
    fn pvd_snapshot_after_two_adds() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("run.pvd");
        let mut w = PvdWriter::create(&p).unwrap();
        w.add(0.0, "run_0000.vtu").unwrap();
        w.add(0.25, "vtu/run_0001.vtu").unwrap();
        insta::assert_snapshot!(fs::read_to_string(&p).unwrap());
    }

    #[test]
    fn pvd_is_well_formed_after_every_add() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("run.pvd");
        let mut w = PvdWriter::create(&p).unwrap();
        check_pvd(&fs::read_to_string(&p).unwrap(), 0);
        w.add(0.0, "a_0.vtu").unwrap();
        check_pvd(&fs::read_to_string(&p).unwrap(), 1);
        w.add(1e-3, "a_1.vtu").unwrap();
        check_pvd(&fs::read_to_string(&p).unwrap(), 2);
        assert_eq!(w.len(), 2);
        // No temporary files left behind.
        assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn pvd_refuses_nan_time_and_keeps_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("run.pvd");
        let mut w = PvdWriter::create(&p).unwrap();
        w.add(0.0, "a_0.vtu").unwrap();
        let err = w.add(f64::NAN, "a_1.vtu").unwrap_err();
        assert!(matches!(err, OutputError::NonFinite { ref field, point: 1 } if field == "time"));
        assert_eq!(w.len(), 1);
        check_pvd(&fs::read_to_string(&p).unwrap(), 1);
    }

    #[test]
    fn pvd_escapes_file_names() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("run.pvd");
        let mut w = PvdWriter::create(&p).unwrap();
        w.add(1.0, "a&b.vtu").unwrap();
        assert!(fs::read_to_string(&p).unwrap().contains(r#"file="a&amp;b.vtu""#));
    }
}
