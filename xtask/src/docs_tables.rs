//! `cargo xtask verify --update-docs`: the result tables of docs/verification.md written by
//! the run that produced them, not copied by hand.
//!
//! A report section marks a table with `<!-- table: ID -->` on the line before it
//! (`Report::mark_table` in the binary's `report.rs`). A table of the docs that
//! is generated carries the marker `<!-- table: ID, cargo xtask verify --quick -->` (or
//! without `--quick`, for the full sweep) on the line before it; a run of that mode
//! replaces the table's rows (the consecutive lines that start with `|`) by the report's.

use anyhow::{bail, Result};

/// The marker of table `id` in a report.
pub fn report_marker(id: &str) -> String {
    format!("<!-- table: {id} -->")
}

/// The table lines that follow line `at` of `lines`: consecutive lines starting with `|`.
fn table_after<'l, 'a>(lines: &'l [&'a str], at: usize) -> &'l [&'a str] {
    let start = (at + 1).min(lines.len());
    let len = lines[start..].iter().take_while(|l| l.starts_with('|')).count();
    &lines[start..start + len]
}

/// The id of a docs marker line for a run of mode `quick`: `<!-- table: ID, cargo xtask
/// verify --quick -->` for a quick run, `<!-- table: ID, cargo xtask verify -->` for the
/// full one; `None` for any other line.
fn docs_marker(line: &str, quick: bool) -> Option<&str> {
    let inner = line.trim().strip_prefix("<!-- table: ")?.strip_suffix(" -->")?;
    let (id, mode) = inner.split_once(", ")?;
    let wanted = if quick { "cargo xtask verify --quick" } else { "cargo xtask verify" };
    (mode == wanted).then_some(id)
}

/// `docs` with every table marked for this mode replaced by the report's table of the same
/// id, and the ids replaced; a marked table the report lacks (its section did not run) is
/// left as it is. A marked table the report has but the docs marker is not followed by a
/// table is an error.
pub fn update(docs: &str, report: &str, quick: bool) -> Result<(String, Vec<String>)> {
    let report_lines: Vec<&str> = report.lines().collect();
    let lines: Vec<&str> = docs.lines().collect();
    let (mut out, mut replaced) = (Vec::with_capacity(lines.len()), Vec::new());
    let mut k = 0;
    while k < lines.len() {
        out.push(lines[k].to_string());
        let Some(id) = docs_marker(lines[k], quick) else {
            k += 1;
            continue;
        };
        let old = table_after(&lines, k);
        let from_report = report_lines.iter().position(|l| l.trim() == report_marker(id));
        match from_report.map(|at| table_after(&report_lines, at)) {
            Some(new) if !new.is_empty() => {
                if old.is_empty() {
                    bail!("docs line {}: the marker of table {id} is not followed by a table", k + 1);
                }
                out.extend(new.iter().map(|l| l.to_string()));
                replaced.push(id.to_string());
            }
            _ => out.extend(old.iter().map(|l| l.to_string())),
        }
        k += 1 + old.len();
    }
    let mut text = out.join("\n");
    if docs.ends_with('\n') {
        text.push('\n');
    }
    Ok((text, replaced))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The quick run replaces its marked table and leaves the full sweep's, the text
    /// around them, and a table whose section did not run; a marker without a table is
    /// refused.
    #[test]
    fn marked_tables_take_the_report_rows_of_their_mode() {
        let docs = "# V\n\ntext\n<!-- table: A, cargo xtask verify --quick -->\n| a |\n|---|\n| 1 |\nafter\n\
                    <!-- table: A, cargo xtask verify -->\n| a |\n|---|\n| 9 |\n\
                    <!-- table: B, cargo xtask verify --quick -->\n| b |\n|---|\n| 2 |\nend\n";
        let report = "## A\n\n<!-- table: A -->\n| a |\n|---|\n| 3 |\n| 4 |\n\nmore\n";
        let (text, ids) = update(docs, report, true).unwrap();
        assert_eq!(ids, vec!["A"]);
        assert_eq!(
            text,
            "# V\n\ntext\n<!-- table: A, cargo xtask verify --quick -->\n| a |\n|---|\n| 3 |\n| 4 |\nafter\n\
             <!-- table: A, cargo xtask verify -->\n| a |\n|---|\n| 9 |\n\
             <!-- table: B, cargo xtask verify --quick -->\n| b |\n|---|\n| 2 |\nend\n"
        );
        let (full, ids) = update(docs, report, false).unwrap();
        assert_eq!(ids, vec!["A"]);
        assert!(full.contains("after\n<!-- table: A, cargo xtask verify -->\n| a |\n|---|\n| 3 |\n| 4 |\n<!--"));
        assert!(update("<!-- table: A, cargo xtask verify --quick -->\ntext\n", report, true).is_err());
    }
}
