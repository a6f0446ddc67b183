//! CSV writers: an append-only log with a fixed header, and atomic
//! whole-table writes.

use std::borrow::Cow;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::{fmt_f64, io_err, write_atomic, OutputError};

/// One cell of a mixed-type CSV row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CsvCell<'a> {
    /// An integer (step counts, iteration numbers, flags).
    Int(i64),
    /// A float, written in shortest round-trip form.
    Float(f64),
    /// Text, quoted if it contains a comma, quote or line break.
    Text(&'a str),
}

impl From<i64> for CsvCell<'_> {
    fn from(v: i64) -> Self {
        CsvCell::Int(v)
    }
}

impl From<f64> for CsvCell<'_> {
    fn from(v: f64) -> Self {
        CsvCell::Float(v)
    }
}

impl<'a> From<&'a str> for CsvCell<'a> {
    fn from(v: &'a str) -> Self {
        CsvCell::Text(v)
    }
}

/// Quotes a CSV field (RFC 4180) when needed.
fn quote(s: &str) -> Cow<'_, str> {
    let needs =
        s.contains([',', '"', '\n', '\r']) || s.starts_with(char::is_whitespace) || s.ends_with(char::is_whitespace);
    if needs {
        Cow::Owned(format!("\"{}\"", s.replace('"', "\"\"")))
    } else {
        Cow::Borrowed(s)
    }
}

fn cell_text<'a>(c: &CsvCell<'a>) -> Cow<'a, str> {
    match *c {
        CsvCell::Int(i) => Cow::Owned(i.to_string()),
        CsvCell::Float(x) => Cow::Owned(fmt_f64(x)),
        CsvCell::Text(s) => quote(s),
    }
}

/// An append-only CSV file with a fixed header.
///
/// Every row is checked against the header's arity and flushed as soon as
/// it is written, so a crash keeps all rows written so far. Floats use the
/// shortest representation that round-trips (`Display`, or exponent form for
/// very small/large magnitudes). Non-finite floats are written as `NaN`,
/// `inf`, `-inf` (a log should record a diverging residual, not fail on it).
#[derive(Debug)]
pub struct CsvWriter {
    path: PathBuf,
    columns: usize,
    out: BufWriter<File>,
    /// Bytes in the file (every row is flushed).
    bytes: u64,
}

impl CsvWriter {
    /// Creates (or truncates) `path` and writes the header line.
    pub fn create(path: impl AsRef<Path>, header: &[&str]) -> Result<Self, OutputError> {
        let path = path.as_ref().to_path_buf();
        let file = File::create(&path).map_err(io_err(&path))?;
        let mut w = Self { columns: header.len(), out: BufWriter::new(file), path, bytes: 0 };
        w.write_line(&header_line(header))?;
        Ok(w)
    }

    /// Go on appending to `path`, written by a run that had written `bytes` of it when it
    /// saved its checkpoint: what came after is cut off (rows of steps the resumed run will
    /// write again, or a row half written when the run was killed). Refused unless the file
    /// has `header` and at least `bytes` bytes.
    pub fn resume(path: impl AsRef<Path>, header: &[&str], bytes: u64) -> Result<Self, OutputError> {
        use std::io::{BufRead, BufReader, Seek};
        let path = path.as_ref().to_path_buf();
        let resume = |what: String| OutputError::Resume { path: path.clone(), what };
        let mut file = std::fs::OpenOptions::new().read(true).write(true).open(&path).map_err(io_err(&path))?;
        let found = file.metadata().map_err(io_err(&path))?.len();
        if found < bytes {
            return Err(resume(format!("it holds {found} bytes, fewer than the {bytes} the checkpoint counted")));
        }
        let mut first = String::new();
        BufReader::new(&mut file).read_line(&mut first).map_err(io_err(&path))?;
        if first.trim_end_matches('\n') != header_line(header) {
            return Err(resume("its columns are not this run's".into()));
        }
        file.set_len(bytes).map_err(io_err(&path))?;
        file.seek(std::io::SeekFrom::End(0)).map_err(io_err(&path))?;
        Ok(Self { columns: header.len(), out: BufWriter::new(file), path, bytes })
    }

    /// [`CsvWriter::create`], or [`CsvWriter::resume`] after `resume_at` bytes when given.
    pub fn open(path: impl AsRef<Path>, header: &[&str], resume_at: Option<u64>) -> Result<Self, OutputError> {
        match resume_at {
            Some(bytes) => Self::resume(path, header, bytes),
            None => Self::create(path, header),
        }
    }

    /// Bytes in the file so far (all of them on disk: rows are flushed as written).
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// The path of the CSV file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Number of columns (the header's length).
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Appends a row of floats; its length must match the header.
    pub fn row(&mut self, values: &[f64]) -> Result<(), OutputError> {
        self.check_arity(values.len())?;
        let line: Vec<String> = values.iter().map(|&v| fmt_f64(v)).collect();
        self.write_line(&line.join(","))
    }

    /// Appends a row of mixed integer/float/text cells; its length must
    /// match the header.
    pub fn row_mixed(&mut self, cells: &[CsvCell]) -> Result<(), OutputError> {
        self.check_arity(cells.len())?;
        let line: Vec<Cow<str>> = cells.iter().map(cell_text).collect();
        self.write_line(&line.join(","))
    }

    fn check_arity(&self, found: usize) -> Result<(), OutputError> {
        if found == self.columns {
            Ok(())
        } else {
            Err(OutputError::Shape { field: "row".to_owned(), expected: self.columns, found })
        }
    }

    fn write_line(&mut self, line: &str) -> Result<(), OutputError> {
        let r = (|| {
            self.out.write_all(line.as_bytes())?;
            self.out.write_all(b"\n")?;
            self.out.flush()
        })();
        r.map_err(io_err(&self.path))?;
        self.bytes += line.len() as u64 + 1;
        Ok(())
    }
}

/// The header line: the column names, quoted where needed.
fn header_line(header: &[&str]) -> String {
    let line: Vec<Cow<str>> = header.iter().map(|h| quote(h)).collect();
    line.join(",")
}

/// Writes a whole CSV table atomically (temporary file + rename): a header
/// line, then one row per index of the equally long `columns`
/// (`columns[j][i]` is row `i`, column `j`).
///
/// Errors with [`OutputError::Shape`] if the number of columns differs from
/// the header (`field = "columns"`) or a column's length differs from the
/// first column's (`field` = that column's header name).
pub fn write_csv_table(path: impl AsRef<Path>, header: &[&str], columns: &[&[f64]]) -> Result<(), OutputError> {
    let path = path.as_ref();
    if columns.len() != header.len() {
        return Err(OutputError::Shape { field: "columns".to_owned(), expected: header.len(), found: columns.len() });
    }
    let rows = columns.first().map_or(0, |c| c.len());
    for (name, col) in header.iter().zip(columns) {
        if col.len() != rows {
            return Err(OutputError::Shape { field: (*name).to_owned(), expected: rows, found: col.len() });
        }
    }
    write_atomic(path, |w| {
        writeln!(w, "{}", header_line(header))?;
        let mut line = String::new();
        for i in 0..rows {
            line.clear();
            for (j, col) in columns.iter().enumerate() {
                if j > 0 {
                    line.push(',');
                }
                line.push_str(&fmt_f64(col[i]));
            }
            writeln!(w, "{line}")?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A resumed log is cut back to the checkpoint's length (a row half written by a killed
    /// run goes) and goes on; a file with other columns, or shorter than the checkpoint
    /// says, is refused and left as it was.
    #[test]
    fn a_resumed_log_goes_on_from_the_checkpoint() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("log.csv");
        let mut w = CsvWriter::create(&p, &["step", "x"]).unwrap();
        w.row(&[1.0, 0.5]).unwrap();
        let saved = w.bytes();
        w.row(&[2.0, 0.25]).unwrap();
        drop(w);
        std::fs::write(&p, std::fs::read_to_string(&p).unwrap() + "3,0.1").unwrap();
        assert!(matches!(CsvWriter::resume(&p, &["step", "y"], saved), Err(OutputError::Resume { .. })));
        assert!(matches!(CsvWriter::resume(&p, &["step", "x"], 1000), Err(OutputError::Resume { .. })));
        let mut w = CsvWriter::resume(&p, &["step", "x"], saved).unwrap();
        w.row(&[2.0, 0.75]).unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "step,x\n1,0.5\n2,0.75\n");
        assert_eq!(w.bytes(), std::fs::metadata(&p).unwrap().len());
    }
    use std::fs;

    #[test]
    fn csv_log_snapshot() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("log.csv");
        let mut w = CsvWriter::create(&p, &["step", "time", "residual", "note"]).unwrap();
        w.row(&[0.0, 0.0, 1.0, 0.0]).unwrap();
        w.row_mixed(&[
            CsvCell::Int(1),
            CsvCell::Float(0.1),
            CsvCell::Float(3.2e-11),
            CsvCell::Text("converged, 3 iters"),
        ])
        .unwrap();
        w.row_mixed(&[2i64.into(), 0.2.into(), f64::NAN.into(), "say \"hi\"".into()]).unwrap();
        // Rows are on disk without dropping the writer.
        insta::assert_snapshot!(fs::read_to_string(&p).unwrap());
    }

    #[test]
    fn csv_table_snapshot() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("points_final.csv");
        let x = [0.0, 0.5, 1.0];
        let y = [0.25, 0.25, 0.75];
        let p_col = [-1e3, 2.5, 1.0 / 3.0];
        write_csv_table(&p, &["x", "y", "p"], &[&x, &y, &p_col]).unwrap();
        insta::assert_snapshot!(fs::read_to_string(&p).unwrap());
    }

    #[test]
    fn csv_values_round_trip() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("rt.csv");
        let vals = [0.1 + 0.2, -1e-300, 1.0 / 7.0, 6.02214076e23, -0.0];
        let mut w = CsvWriter::create(&p, &["a", "b", "c", "d", "e"]).unwrap();
        w.row(&vals).unwrap();
        let text = fs::read_to_string(&p).unwrap();
        let row = text.lines().nth(1).unwrap();
        let back: Vec<f64> = row.split(',').map(|s| s.parse().unwrap()).collect();
        for (a, b) in vals.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.to_bits());
        }
    }

    #[test]
    fn csv_arity_mismatch() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("log.csv");
        let mut w = CsvWriter::create(&p, &["a", "b"]).unwrap();
        let err = w.row(&[1.0]).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 2, found: 1 } if field == "row"
        ));
        let err = w.row_mixed(&[CsvCell::Int(1), CsvCell::Int(2), CsvCell::Int(3)]).unwrap_err();
        assert!(matches!(err, OutputError::Shape { expected: 2, found: 3, .. }));
        // Nothing but the header was written.
        assert_eq!(fs::read_to_string(&p).unwrap(), "a,b\n");
    }

    #[test]
    fn csv_table_shape_errors() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.csv");
        let a = [1.0, 2.0];
        let b = [1.0];
        let err = write_csv_table(&p, &["a", "b"], &[&a]).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 2, found: 1 } if field == "columns"
        ));
        let err = write_csv_table(&p, &["a", "b"], &[&a, &b]).unwrap_err();
        assert!(matches!(
            err,
            OutputError::Shape { ref field, expected: 2, found: 1 } if field == "b"
        ));
        assert!(!p.exists());
    }

    #[test]
    fn csv_header_quoting() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("q.csv");
        CsvWriter::create(&p, &["sigma_xx [Pa]", "a,b"]).unwrap();
        assert_eq!(fs::read_to_string(&p).unwrap(), "sigma_xx [Pa],\"a,b\"\n");
    }
}
