//! The docs hold together: every `docs/….md §…` reference in the tree names a section that
//! exists, every code path the docs name exists, the stages docs/theory.md §1 maps to
//! functions are those functions, and no file cites a file outside the repository.

use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every text file of the repository that can cite something: sources, docs, scenes,
/// manifests and scripts (build outputs and version control left out).
fn text_files() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in fs::read_dir(dir).unwrap().flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().into_owned();
            if path.is_dir() {
                if !matches!(name.as_str(), "target" | ".git" | "out" | "snapshots") {
                    walk(&path, out);
                }
            } else if ["rs", "md", "ron", "toml", "sh"].iter().any(|e| name.ends_with(&format!(".{e}")))
                || name == "run"
            {
                out.push(path);
            }
        }
    }
    let mut out = Vec::new();
    walk(&root(), &mut out);
    out.sort();
    out
}

/// The section keys of a markdown file: the first word of each heading, without a trailing
/// dot ("## 6. Newton and cut-back" → "6", "### V3. Strip footing" → "V3").
fn section_keys(doc: &str) -> Vec<String> {
    doc.lines()
        .filter(|l| l.starts_with('#'))
        .filter_map(|l| l.trim_start_matches('#').split_whitespace().next())
        .map(|w| w.trim_end_matches('.').to_string())
        .collect()
}

/// Every `§key` in `text` with the docs file it refers to: the nearest `name.md` before it
/// on its line, or `own` (a doc citing its own sections) when there is none.
fn section_references(text: &str, own: Option<&str>) -> Vec<(String, String, usize)> {
    let mut refs = Vec::new();
    for (n, line) in text.lines().enumerate() {
        for (at, _) in line.match_indices('§') {
            let key: String = line[at + '§'.len_utf8()..].chars().take_while(|c| c.is_alphanumeric()).collect();
            let before = &line[..at];
            let file = before.rfind(".md").and_then(|end| {
                let name: Vec<char> =
                    before[..end].chars().rev().take_while(|c| c.is_alphanumeric() || *c == '-' || *c == '_').collect();
                Some(name.into_iter().rev().collect::<String>()).filter(|f| !f.is_empty())
            });
            if let Some(file) = file.or(own.map(str::to_string)) {
                refs.push((file, key, n + 1));
            }
        }
    }
    refs
}

#[test]
fn every_docs_section_reference_resolves() {
    let mut checked = 0;
    let mut broken = Vec::new();
    for path in text_files() {
        let text = fs::read_to_string(&path).unwrap();
        let own = path
            .parent()
            .filter(|p| p.ends_with("docs"))
            .and_then(|_| path.file_stem())
            .map(|s| s.to_string_lossy().into_owned());
        for (file, key, line) in section_references(&text, own.as_deref()) {
            let doc = root().join("docs").join(format!("{file}.md"));
            let ok = fs::read_to_string(&doc).is_ok_and(|d| section_keys(&d).contains(&key));
            if !ok {
                broken.push(format!("{}:{line}: docs/{file}.md §{key}", path.strip_prefix(root()).unwrap().display()));
            }
            checked += 1;
        }
    }
    assert!(checked > 50, "only {checked} references found: the scan is broken");
    assert!(broken.is_empty(), "{} references to sections that do not exist:\n{}", broken.len(), broken.join("\n"));
}

#[test]
fn no_file_cites_a_file_outside_the_repository() {
    // Built from parts, so that this file does not match itself.
    let outside = [
        format!("../{}", "shared"),
        format!("{}.md", "THEORY"),
        format!("{}.md", "DESIGN"),
        format!("{}.md", "VERIFICATION"),
        format!("{} §", "THEORY"),
    ];
    let mut found = Vec::new();
    for path in text_files() {
        let text = fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            if let Some(p) = outside.iter().find(|p| line.contains(p.as_str())) {
                found.push(format!("{}:{}: {p}", path.strip_prefix(root()).unwrap().display(), n + 1));
            }
        }
    }
    assert!(found.is_empty(), "files cite files outside the repository:\n{}", found.join("\n"));
}

/// All Rust sources of the workspace, concatenated per file.
fn sources() -> Vec<(PathBuf, String)> {
    text_files()
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .map(|p| {
            let s = fs::read_to_string(&p).unwrap();
            (p, s)
        })
        .collect()
}

/// Whether `name` is defined in `source`: a function, type, trait, constant, module, public
/// field, or an enum variant (an indented line starting with it).
fn defines(source: &str, name: &str) -> bool {
    let items = ["fn", "struct", "enum", "trait", "const", "type", "mod", "static"];
    source.lines().any(|l| {
        let t = l.trim_start();
        let t = t.strip_prefix("pub(crate) ").or_else(|| t.strip_prefix("pub ")).unwrap_or(t);
        items.iter().any(|k| {
            t.strip_prefix(k).and_then(|r| r.strip_prefix(' ')).is_some_and(|r| {
                r.starts_with(name) && !r[name.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_')
            })
        }) || (t.starts_with(name) && t[name.len()..].starts_with(['(', ' ', ',', '{', ':']) && l.starts_with("    "))
    })
}

#[test]
fn code_the_docs_name_exists() {
    let sources = sources();
    let mut missing = Vec::new();
    for doc in ["theory.md", "verification.md", "robustness.md", "scene-format.md"] {
        let text = fs::read_to_string(root().join("docs").join(doc)).unwrap();
        for token in text.split('`').skip(1).step_by(2) {
            if token.contains("::") && !token.contains(' ') {
                let name = token.rsplit("::").next().unwrap().trim_end_matches("()");
                if !name.is_empty() && !sources.iter().any(|(_, s)| defines(s, name)) {
                    missing.push(format!("docs/{doc}: `{token}`"));
                }
            }
        }
        for word in text.split(|c: char| c.is_whitespace() || "`(),;".contains(c)) {
            let path = word.trim_end_matches(['.', ':']);
            if (path.starts_with("crates/") || path.starts_with("tests/"))
                && path.ends_with(".rs")
                && !root().join(path).exists()
            {
                missing.push(format!("docs/{doc}: {path}"));
            }
        }
    }
    assert!(missing.is_empty(), "the docs name code that does not exist:\n{}", missing.join("\n"));
}

/// docs/theory.md §1 maps each stage of each analysis to its function and file: every row
/// of those tables names a function the file defines.
#[test]
fn the_stages_of_theory_section_1_are_those_functions() {
    let text = fs::read_to_string(root().join("docs/theory.md")).unwrap();
    let section = text.split("\n## ").find(|s| s.starts_with("1.")).expect("docs/theory.md §1");
    let mut rows = 0;
    for line in section.lines().filter(|l| l.starts_with('|')) {
        let cells: Vec<&str> = line.split('|').map(str::trim).filter(|c| !c.is_empty()).collect();
        let [_, function, file] = cells[..] else { continue };
        if !file.ends_with(".rs") {
            continue;
        }
        let name = function.trim_matches('`').rsplit("::").next().unwrap();
        let source =
            fs::read_to_string(root().join(file)).unwrap_or_else(|_| panic!("§1 names {file}, which does not exist"));
        assert!(defines(&source, name), "§1 maps a stage to `{function}`, which {file} does not define");
        rows += 1;
    }
    assert!(rows >= 20, "only {rows} stage rows found in docs/theory.md §1");
}
