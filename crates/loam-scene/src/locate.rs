//! Where in the RON text an error belongs: a `SceneError` names the file, the line and the
//! column of the offending value, found by following a path of keys and list indices
//! through the source (serde keeps no positions once a value is parsed).

use std::path::PathBuf;

/// A scene error, located in its file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}:{line}:{column}: {message}", file.display())]
pub struct SceneError {
    pub file: PathBuf,
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// One step of a path into the scene, for locating an error in the text.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Seg<'a> {
    Key(&'a str),
    Index(usize),
}

/// Line and column (1-based) of the value at `path` in RON `source`, found by scanning:
/// a key is `name:` inside the current range, an index the n-th top-level element of the
/// list or tuple that follows. Falls back to the deepest part found.
pub(super) fn locate(source: &str, path: &[Seg]) -> (usize, usize) {
    let bytes = source.as_bytes();
    let (mut start, mut end) = (0usize, bytes.len());
    for seg in path {
        match *seg {
            Seg::Key(k) => match find_key(source, start, end, k) {
                Some(pos) => {
                    start = pos;
                    end = value_end(bytes, pos + k.len(), end);
                }
                None => break,
            },
            Seg::Index(i) => match nth_element(bytes, start, end, i) {
                Some((s, e)) => {
                    start = s;
                    end = e;
                }
                None => break,
            },
        }
    }
    let line = source[..start].matches('\n').count() + 1;
    let column = start - source[..start].rfind('\n').map_or(0, |p| p + 1) + 1;
    (line, column)
}

/// Position of `key` followed by `:` at nesting depth 0 relative to `start`, within
/// [start, end), skipping strings and comments.
fn find_key(source: &str, start: usize, end: usize, key: &str) -> Option<usize> {
    let bytes = source.as_bytes();
    let mut depth = 0i32;
    let mut i = start;
    // If the range starts at `name:` or an opening bracket, look inside it.
    while i < end {
        match bytes[i] {
            b'"' => i = skip_string(bytes, i),
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                while i < end && bytes[i] != b'\n' {
                    i += 1;
                }
            }
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => depth -= 1,
            _ => {
                if depth <= 1
                    && source[i..end].starts_with(key)
                    && (i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_'))
                {
                    let rest = source[i + key.len()..end].trim_start();
                    if rest.starts_with(':') {
                        return Some(i);
                    }
                }
            }
        }
        i += 1;
    }
    None
}

fn skip_string(bytes: &[u8], mut i: usize) -> usize {
    i += 1;
    while i < bytes.len() && bytes[i] != b'"' {
        if bytes[i] == b'\\' {
            i += 1;
        }
        i += 1;
    }
    i
}

/// End of the value that follows `key:` at `from`: the next top-level comma or closing
/// bracket.
fn value_end(bytes: &[u8], from: usize, end: usize) -> usize {
    let mut depth = 0i32;
    let mut i = from;
    while i < end {
        match bytes[i] {
            b'"' => i = skip_string(bytes, i),
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                if depth == 0 {
                    return i;
                }
                depth -= 1;
            }
            b',' if depth == 0 => return i,
            _ => {}
        }
        i += 1;
    }
    end
}

/// Range of the n-th top-level element of the first list in [start, end).
fn nth_element(bytes: &[u8], start: usize, end: usize, n: usize) -> Option<(usize, usize)> {
    let mut i = start;
    while i < end && bytes[i] != b'[' {
        if bytes[i] == b'"' {
            i = skip_string(bytes, i);
        }
        i += 1;
    }
    i += 1;
    let mut k = 0;
    loop {
        while i < end && (bytes[i].is_ascii_whitespace() || bytes[i] == b',') {
            i += 1;
        }
        if i >= end || bytes[i] == b']' {
            return None;
        }
        let e = value_end(bytes, i, end);
        if k == n {
            return Some((i, e));
        }
        k += 1;
        i = e;
        if i < end && bytes[i] == b']' {
            return None;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{locate, Seg};

    const TEXT: &str = "Scene(\n    // grid: not this one\n    name: \"grid: nor this\",\n    grid: (cells: [1, 2]),\n    bodies: [\n        (a: 1),\n        (a: 2, b: [3, 4]),\n    ],\n)";

    #[test]
    fn a_key_skips_comments_and_strings() {
        assert_eq!(locate(TEXT, &[Seg::Key("grid")]), (4, 5));
        assert_eq!(locate(TEXT, &[Seg::Key("grid"), Seg::Key("cells")]), (4, 12));
    }

    #[test]
    fn an_index_is_the_nth_element_of_the_list() {
        assert_eq!(locate(TEXT, &[Seg::Key("bodies"), Seg::Index(1)]), (7, 9));
        assert_eq!(locate(TEXT, &[Seg::Key("bodies"), Seg::Index(1), Seg::Key("b")]), (7, 16));
        assert_eq!(locate(TEXT, &[Seg::Key("bodies"), Seg::Index(1), Seg::Key("b"), Seg::Index(1)]), (7, 23));
    }

    #[test]
    fn a_missing_part_falls_back_to_the_deepest_found() {
        assert_eq!(locate(TEXT, &[Seg::Key("bodies"), Seg::Index(5)]), (5, 5));
        assert_eq!(locate(TEXT, &[Seg::Key("bodies"), Seg::Index(0), Seg::Key("b")]), (6, 9));
        assert_eq!(locate(TEXT, &[Seg::Key("nowhere")]), (1, 1));
        assert_eq!(locate(TEXT, &[]), (1, 1));
    }
}
