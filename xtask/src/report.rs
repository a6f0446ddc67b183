//! The verification report being written: its markdown, the rows of its bounds table and
//! the folder it goes to; and, once every section has run, the bounds table itself in the
//! markdown and in `summary.csv`.

use anyhow::Result;
use loam::format::output::{CsvCell, CsvWriter};
use loam_verification::Bound;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One row of the bounds table: a figure of one case, checked or not.
pub(crate) struct Row {
    case: String,
    quantity: String,
    value: f64,
    /// The bound the value is checked against; each is declared beside its case in
    /// loam-verification, so the report writer holds no numbers of its own.
    bound: Option<Bound>,
}

impl Row {
    /// A value checked against `bound` where there is one.
    pub fn new(case: impl Into<String>, quantity: impl Into<String>, value: f64, bound: Option<Bound>) -> Self {
        Self { case: case.into(), quantity: quantity.into(), value, bound }
    }

    /// A value checked against `bound`.
    pub fn checked(case: impl Into<String>, quantity: impl Into<String>, value: f64, bound: Bound) -> Self {
        Self::new(case, quantity, value, Some(bound))
    }

    /// A measured figure without a bound.
    pub fn info(case: impl Into<String>, quantity: impl Into<String>, value: f64) -> Self {
        Self::new(case, quantity, value, None)
    }

    /// The bound as the table shows it ("<=0.05") and the verdict ("pass", "FAIL", "n/a").
    fn verdict(&self) -> (String, &'static str) {
        match self.bound {
            Some(b) => (format!("{}{}", b.relation(), b.value), if b.holds(self.value) { "pass" } else { "FAIL" }),
            None => (String::new(), "n/a"),
        }
    }
}

/// The verification report being written: markdown, the bounds table's rows, the folder.
pub(crate) struct Report {
    pub md: String,
    pub rows: Vec<Row>,
    pub out: PathBuf,
    /// Runs of a section may go side by side (`verify --side-by-side`).
    pub side_by_side: bool,
}

/// `run` of every job, results in the jobs' order: in rayon's pool if `side_by_side`, one
/// after another otherwise.
pub fn runs<J: Sync, R: Send>(side_by_side: bool, jobs: &[J], run: impl Fn(&J) -> R + Sync + Send) -> Vec<R> {
    if side_by_side {
        jobs.par_iter().map(run).collect()
    } else {
        jobs.iter().map(run).collect()
    }
}

impl Report {
    /// An empty report under its title, to be written into `out`.
    pub fn new(out: &Path) -> Result<Self> {
        let mut md = String::new();
        writeln!(md, "# loam verification report\n")?;
        Ok(Self { md, rows: Vec::new(), out: out.to_owned(), side_by_side: false })
    }

    /// An empty part of a report, for one section to write into `out`; [`Report::append`]
    /// puts it in its place.
    pub fn part(out: &Path, side_by_side: bool) -> Self {
        Self { md: String::new(), rows: Vec::new(), out: out.to_owned(), side_by_side }
    }

    /// `part`'s markdown and rows after this report's.
    pub fn append(&mut self, part: Report) {
        self.md.push_str(&part.md);
        self.rows.extend(part.rows);
    }

    /// `run` of every job, in order: side by side if the report allows it.
    pub fn runs<J: Sync, R: Send>(&self, jobs: &[J], run: impl Fn(&J) -> R + Sync + Send) -> Vec<R> {
        runs(self.side_by_side, jobs, run)
    }

    /// `a()` and `b()`: side by side if the report allows it.
    pub fn both<A: Send, B: Send>(&self, a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B + Send) -> (A, B) {
        if self.side_by_side {
            rayon::join(a, b)
        } else {
            (a(), b())
        }
    }

    /// Mark the table that follows as table `id`, which `--update-docs` copies into the
    /// docs where they carry its marker (`docs_tables`).
    pub fn mark_table(&mut self, id: &str) -> Result<()> {
        writeln!(self.md, "{}", xtask::docs_tables::report_marker(id))?;
        Ok(())
    }

    /// Append the bounds table (the checked rows) to the markdown and write every row to
    /// `summary.csv`; returns the rows that failed their bound, one line each.
    pub fn bounds_table(&mut self) -> Result<Vec<String>> {
        writeln!(self.md, "## Bounds\n\n| case | quantity | value | bound | pass |\n|---|---|---:|---:|---|")?;
        let mut csv = CsvWriter::create(self.out.join("summary.csv"), &["case", "quantity", "value", "bound", "pass"])?;
        let mut failed = Vec::new();
        for r in &self.rows {
            let (bound_s, pass_s) = r.verdict();
            if pass_s == "FAIL" {
                failed.push(format!("{} {} = {:.4e} (bound {bound_s})", r.case, r.quantity, r.value));
            }
            csv.row_mixed(&[
                CsvCell::Text(&r.case),
                CsvCell::Text(&r.quantity),
                CsvCell::Float(r.value),
                CsvCell::Text(&bound_s),
                CsvCell::Text(pass_s),
            ])?;
            if r.bound.is_some() {
                writeln!(self.md, "| {} | {} | {:.4e} | {bound_s} | {pass_s} |", r.case, r.quantity, r.value)?;
            }
        }
        Ok(failed)
    }
}
