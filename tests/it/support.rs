//! What several test modules share: running a scene given as text, and reading the CSV
//! files a run writes.

use loam::run::run_scene;
use loam::scene::LoadedScene;
use std::path::Path;

/// Rows of a CSV file as (header, rows).
pub fn table(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    (header, lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect())
}

/// The index of the column `name` of `header`.
pub fn column(header: &[String], name: &str) -> usize {
    header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
}

/// Run `text` as a scene into a temporary directory, which is returned.
pub fn run(text: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let scene = LoadedScene::parse(Path::new("scene.ron"), text.to_string()).unwrap();
    run_scene(&scene, dir.path(), &mut |_| {}).unwrap();
    dir
}
