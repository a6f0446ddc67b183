//! The output folder of a run: what in it is loam's, and what a new run does with it.
//!
//! A run writes `loam_run.txt` (the scene file it ran and loam's version) beside its
//! outputs. A new run into a folder removes the temporary files a killed run left
//! (`.points_00012.vtu.XXXXXX.tmp`), replaces the outputs of an earlier run of the same
//! scene, and refuses a folder that holds another scene's outputs unless told to clear it
//! (`loam run --overwrite`): frames of two scenes side by side in one folder read as one
//! run. Only files with the names loam writes are ever removed.

use std::path::{Path, PathBuf};

/// The file that says which scene's outputs a folder holds.
const MARKER: &str = "loam_run.txt";

/// Why an output folder was not used.
#[derive(Debug, thiserror::Error)]
pub enum OutputDirError {
    #[error("cannot prepare the output folder {}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error(
        "the output folder {} holds the outputs of another run ({other}); give another --out, or \
         --overwrite to remove them (only loam's files are removed)",
        dir.display()
    )]
    OtherRun { dir: PathBuf, other: String },
}

/// Whether `name` is a file a run writes: its frames and collection, its CSV files, the
/// marker, or a temporary file of one of them.
fn is_loam_output(name: &str) -> bool {
    let name = match name.strip_prefix('.').and_then(|n| n.strip_suffix(".tmp")) {
        // `.NAME.XXXXXX.tmp`: the name of the file it was to become, and a random suffix.
        Some(inner) => inner.rsplit_once('.').map_or(inner, |(file, _)| file),
        None => name,
    };
    let frame = name.strip_prefix("points_").and_then(|n| n.strip_suffix(".vtu"));
    frame.is_some_and(|k| !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
        || matches!(
            name,
            "points.pvd"
                | "run_log.csv"
                | "history.csv"
                | "points_final.csv"
                | "strength_reduction.csv"
                | MARKER
                | crate::checkpoint::CHECKPOINT_FILE
        )
        || crate::run_plots::PLOT_FILES.contains(&name)
}

/// The names of loam's files in `dir` (none if it does not exist), sorted.
fn loam_files(dir: &Path) -> Result<Vec<PathBuf>, OutputDirError> {
    let io = |source| io_error(dir, source);
    let entries = match std::fs::read_dir(dir) {
        Ok(entries) => entries,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(io(e)),
    };
    let mut files = Vec::new();
    for entry in entries {
        let entry = entry.map_err(io)?;
        if entry.file_name().to_str().is_some_and(is_loam_output) && entry.file_type().map_err(io)?.is_file() {
            files.push(entry.path());
        }
    }
    files.sort();
    Ok(files)
}

/// Remove loam's files from `dir`, whatever run wrote them (`loam run --overwrite`).
pub fn clear_output_dir(dir: &Path) -> Result<(), OutputDirError> {
    for file in loam_files(dir)? {
        std::fs::remove_file(&file).map_err(|source| io_error(&file, source))?;
    }
    Ok(())
}

/// Remove the temporary files a killed run left in `dir` (a resumed run's folder, whose
/// outputs stay).
pub fn remove_temp_files(dir: &Path) -> Result<(), OutputDirError> {
    for file in loam_files(dir)? {
        if file.file_name().is_some_and(|n| n.to_string_lossy().ends_with(".tmp")) {
            std::fs::remove_file(&file).map_err(|source| io_error(&file, source))?;
        }
    }
    Ok(())
}

/// The scene file whose outputs `dir` holds, as its `loam_run.txt` says.
pub fn marked_scene(dir: &Path) -> Option<PathBuf> {
    let text = std::fs::read_to_string(dir.join(MARKER)).ok()?;
    text.lines().next()?.strip_prefix("scene: ").map(PathBuf::from)
}

/// Make `dir` ready for a run of the scene file `scene`: created if missing; emptied of
/// loam's files if they are an earlier run's of the same scene or temporary files; refused
/// if they are another scene's (or of a run that did not say). Then the marker is written.
pub fn prepare_output_dir(dir: &Path, scene: &Path) -> Result<(), OutputDirError> {
    std::fs::create_dir_all(dir).map_err(|source| io_error(dir, source))?;
    let this = marker_text(scene);
    let files = loam_files(dir)?;
    let marker = dir.join(MARKER);
    let outputs = files.iter().any(|f| !f.file_name().is_some_and(|n| n.to_string_lossy().ends_with(".tmp")));
    if outputs {
        let earlier = std::fs::read_to_string(&marker).unwrap_or_default();
        if earlier.lines().next() != this.lines().next() {
            let other = earlier.lines().next().map_or("no loam_run.txt says which".to_string(), str::to_string);
            return Err(OutputDirError::OtherRun { dir: dir.to_owned(), other });
        }
    }
    clear_output_dir(dir)?;
    std::fs::write(&marker, this).map_err(|source| io_error(&marker, source))
}

fn io_error(path: &Path, source: std::io::Error) -> OutputDirError {
    OutputDirError::Io { path: path.to_owned(), source }
}

/// The marker's text: the scene file (canonical where it exists) and loam's version.
fn marker_text(scene: &Path) -> String {
    let scene = std::fs::canonicalize(scene).unwrap_or_else(|_| scene.to_owned());
    format!("scene: {}\nloam: {}\n", scene.display(), env!("CARGO_PKG_VERSION"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;

    #[test]
    fn loam_outputs_are_known_by_name() {
        for name in [
            "points_00012.vtu",
            "points.pvd",
            "run_log.csv",
            ".points_00012.vtu.a1B2c3.tmp",
            ".run_log.csv.xYz123.tmp",
            "checkpoint.loam",
            ".checkpoint.loam.AbC123.tmp",
        ] {
            assert!(is_loam_output(name), "{name}");
        }
        for name in ["notes.txt", "points_final.vtu", "points_.vtu", "my.csv", ".bashrc", ".notes.txt.abcdef.tmp"] {
            assert!(!is_loam_output(name), "{name}");
        }
    }

    /// A killed run's temporary files go; a re-run of the same scene replaces its frames
    /// (one the new run would not write included); another scene's folder is refused with
    /// nothing removed, and cleared on request with the user's own files kept.
    #[test]
    fn a_run_replaces_its_own_outputs_and_refuses_another_scenes() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out");
        let (a, b) = (dir.path().join("a.ron"), dir.path().join("b.ron"));
        prepare_output_dir(&out, &a).unwrap();
        for f in ["points_00099.vtu", ".points_00100.vtu.Qw3rTy.tmp", "notes.txt"] {
            fs::write(out.join(f), "x").unwrap();
        }
        prepare_output_dir(&out, &a).unwrap();
        let left: Vec<String> =
            fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        let mut left = left;
        left.sort();
        assert_eq!(left, ["loam_run.txt", "notes.txt"]);
        fs::write(out.join("points_00001.vtu"), "x").unwrap();
        let e = prepare_output_dir(&out, &b).unwrap_err();
        assert!(e.to_string().contains("a.ron") && e.to_string().contains("--overwrite"), "{e}");
        assert!(out.join("points_00001.vtu").exists());
        clear_output_dir(&out).unwrap();
        prepare_output_dir(&out, &b).unwrap();
        assert!(!out.join("points_00001.vtu").exists() && out.join("notes.txt").exists());
        assert!(fs::read_to_string(out.join(MARKER)).unwrap().contains("b.ron"));
    }
}
