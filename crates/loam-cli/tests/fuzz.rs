//! Scene fuzzing on stable Rust: every example scene, mutated at random — a number pushed
//! to 0, negated, to ±1e±308, NaN or infinity; a token deleted or doubled; a vector given
//! one entry too many or too few; a name swapped for another of the file's — fed to
//! `loam check` and to the first steps of `loam run`, each in its own process under a time
//! limit and `--max-memory`. No case may panic, hang or write a NaN, and every refusal of
//! `loam check` names its place in the file (`case.ron:LINE:COLUMN`).
//!
//! CI runs a few hundred cases; more on demand, with a seed of one's choosing:
//!
//! ```text
//! LOAM_FUZZ_CASES=10000 LOAM_FUZZ_RUNS=1000 LOAM_FUZZ_SEED=7 \
//!     cargo test --release -p loam-cli --test fuzz -- --nocapture
//! ```

mod common;
use common::{env_or, Rng};

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Time allowed to `loam check` on one case, and to the first steps of `loam run`; far
/// above what any case takes (tens of milliseconds, a few seconds), so only a hang trips
/// it.
const CHECK_LIMIT: Duration = Duration::from_secs(60);
const RUN_LIMIT: Duration = Duration::from_secs(120);
/// Steps of each run, and the memory a case may ask for.
const RUN_STEPS: &str = "3";
const MAX_MEMORY: &str = "2G";

/// The examples small enough to run a few steps of in CI (the strength-reduction scenes
/// search their factor of safety before the first step; `loam check` takes every example).
const RUNNABLE: [&str; 15] = [
    "cavity_sphere.ron",
    "column.ron",
    "column_fem.ron",
    "disks.ron",
    "vibrating_bar.ron",
    "footing_arc_length.ron",
    "footing_circular.ron",
    "footing_load_control.ron",
    "footing_rigid_explicit.ron",
    "footing_von_mises.ron",
    "granular_collapse_explicit.ron",
    "landslide_wall_explicit.ron",
    "retaining_wall_explicit.ron",
    "slope_runout_explicit.ron",
    "slope_runout_implicit.ron",
];

/// A token of RON text: its byte range and what kind it is.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Number,
    Name,
    Text,
    Punct,
}

/// The tokens of `source`, comments and white space left out.
fn tokens(source: &str) -> Vec<(usize, usize, Kind)> {
    let b = source.as_bytes();
    let (mut i, mut out) = (0, Vec::new());
    while i < b.len() {
        let c = b[i];
        let start = i;
        if c == b'/' && b.get(i + 1) == Some(&b'/') {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
            continue;
        } else if c.is_ascii_whitespace() {
            i += 1;
            continue;
        } else if c.is_ascii_digit() || (c == b'-' && b.get(i + 1).is_some_and(u8::is_ascii_digit)) {
            i += 1;
            while i < b.len()
                && (b[i].is_ascii_alphanumeric()
                    || b[i] == b'.'
                    || b[i] == b'_'
                    || ((b[i] == b'-' || b[i] == b'+') && matches!(b[i - 1], b'e' | b'E')))
            {
                i += 1;
            }
            out.push((start, i, Kind::Number));
        } else if c.is_ascii_alphabetic() || c == b'_' {
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push((start, i, Kind::Name));
        } else if c == b'"' {
            i += 1;
            while i < b.len() && b[i] != b'"' {
                i += 1;
            }
            i = (i + 1).min(b.len());
            out.push((start, i, Kind::Text));
        } else {
            i += source[i..].chars().next().map_or(1, char::len_utf8);
            out.push((start, i, Kind::Punct));
        }
    }
    out
}

/// One random mutation of `source`; of a number only if `numbers_only` (most other
/// mutations break the syntax, so the runs, which need a valid scene to step, take these).
fn mutate(source: &str, rng: &mut Rng, numbers_only: bool) -> String {
    let toks = tokens(source);
    let of = |kind| toks.iter().filter(|t| t.2 == kind).copied().collect::<Vec<_>>();
    let pick = |list: &[(usize, usize, Kind)], rng: &mut Rng| list[rng.below(list.len())];
    let replace = |(s, e, _): (usize, usize, Kind), with: &str| format!("{}{with}{}", &source[..s], &source[e..]);
    match if numbers_only { 0 } else { rng.below(6) } {
        0 | 1 => {
            let t = pick(&of(Kind::Number), rng);
            let x = &source[t.0..t.1];
            let negated = x.strip_prefix('-').map_or(format!("-{x}"), str::to_string);
            let pushed = format!("{x}e6");
            let values = [
                "0",
                "0.0",
                negated.as_str(),
                "1e308",
                "-1e308",
                "1e-308",
                "NaN",
                "inf",
                "-inf",
                "1e9",
                pushed.as_str(),
            ];
            replace(t, values[rng.below(values.len())])
        }
        2 => replace(pick(&toks, rng), ""),
        3 => {
            let t = pick(&toks, rng);
            replace(t, &format!("{0} {0}", &source[t.0..t.1]))
        }
        4 => {
            // A vector one entry longer or shorter: the number before a `]`.
            let closes: Vec<usize> = (1..toks.len())
                .filter(|&k| &source[toks[k].0..toks[k].1] == "]" && toks[k - 1].2 == Kind::Number)
                .collect();
            match closes.get(rng.below(closes.len())) {
                Some(&k) if rng.below(2) == 0 => replace(toks[k], ", 1.0]"),
                Some(&k) => {
                    let (s, e, _) = toks[k - 1];
                    let before = source[..s].trim_end().trim_end_matches(',');
                    format!("{before}{}", &source[e..])
                }
                None => source.to_string(),
            }
        }
        _ => {
            let names = of(Kind::Name);
            let other = pick(&names, rng);
            replace(pick(&names, rng), &source[other.0..other.1])
        }
    }
}

/// What a child process did within its limit: exit code, stderr, or `None` on timeout.
/// Its stderr goes to a file beside the case, so that a long message cannot fill a pipe
/// and stall the child into a false hang.
fn run_limited(args: &[&std::ffi::OsStr], limit: Duration, log: &Path) -> Option<(Option<i32>, String)> {
    let stderr = std::fs::File::create(log).expect("a log file in the temporary folder");
    let mut child = Command::new(env!("CARGO_BIN_EXE_loam"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(stderr)
        .spawn()
        .expect("the loam binary runs");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("waiting on loam") {
            return Some((status.code(), std::fs::read_to_string(log).unwrap_or_default()));
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A failed case, with what reproduces it.
fn failure(case: usize, seed: u64, scene: &Path, what: &str) -> String {
    let text = std::fs::read_to_string(scene).unwrap_or_default();
    format!("case {case} (seed {seed}): {what}\n--- scene ---\n{text}")
}

/// Whether `text` (a CSV file) holds a NaN or an infinity outside the columns that are NaN
/// by definition (the reactions and residual of an explicit run's log).
fn non_finite_in(path: &Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else { return false };
    text.split([',', '\n']).any(|v| matches!(v.trim().to_ascii_lowercase().as_str(), "nan" | "inf" | "-inf"))
}

fn examples() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let mut all: Vec<(String, String)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ron"))
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read_to_string(&p).unwrap()))
        .collect();
    all.sort();
    all
}

/// `loam check` on mutated scenes: exit 0 or 1 (never a panic's 101 or a signal), within
/// the limit, and every refusal at a place in the case file.
#[test]
fn mutated_scenes_are_checked_without_panic_or_hang() {
    let (cases, seed) = (env_or("LOAM_FUZZ_CASES", 500) as usize, env_or("LOAM_FUZZ_SEED", 1));
    let examples = examples();
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
    let (mut refused, start) = (0, Instant::now());
    for case in 0..cases {
        let (_, source) = &examples[rng.below(examples.len())];
        let mut text = source.clone();
        for _ in 0..1 + rng.below(3) {
            text = mutate(&text, &mut rng, false);
        }
        let scene: PathBuf = dir.path().join("case.ron");
        std::fs::write(&scene, &text).unwrap();
        let args = ["check".as_ref(), scene.as_os_str(), "--max-memory".as_ref(), MAX_MEMORY.as_ref()];
        let Some((code, stderr)) = run_limited(&args, CHECK_LIMIT, &dir.path().join("stderr.txt")) else {
            panic!("{}", failure(case, seed, &scene, "loam check did not finish"));
        };
        match code {
            Some(0) => {}
            Some(1) => {
                refused += 1;
                let placed = stderr.lines().any(|l| {
                    l.split("case.ron:").nth(1).is_some_and(|rest| {
                        let mut parts = rest.splitn(3, ':');
                        parts.next().is_some_and(|n| n.parse::<usize>().is_ok_and(|n| n > 0))
                            && parts.next().is_some_and(|n| n.parse::<usize>().is_ok())
                    })
                });
                assert!(placed, "{}", failure(case, seed, &scene, &format!("refused without a place: {stderr}")));
            }
            other => panic!("{}", failure(case, seed, &scene, &format!("exit {other:?}: {stderr}"))),
        }
    }
    println!("{cases} mutated scenes checked in {:.1} s, {refused} refused", start.elapsed().as_secs_f64());
}

/// The first steps of `loam run` on mutated runnable scenes: exit 0 or 1, within the
/// limit, and no NaN or infinity in the CSV outputs (the VTU writer refuses non-finite
/// values itself).
#[test]
fn mutated_scenes_run_without_panic_hang_or_nan() {
    let (runs, seed) = (env_or("LOAM_FUZZ_RUNS", 24) as usize, env_or("LOAM_FUZZ_SEED", 1));
    let examples: Vec<(String, String)> =
        examples().into_iter().filter(|(n, _)| RUNNABLE.contains(&n.as_str())).collect();
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Rng(seed.wrapping_mul(0xd1b5_4a32_d192_ed03) | 1);
    let (mut failed, start) = (0, Instant::now());
    for case in 0..runs {
        let (_, source) = &examples[case % examples.len()];
        let text = mutate(source, &mut rng, true);
        let scene = dir.path().join("case.ron");
        std::fs::write(&scene, &text).unwrap();
        let out = dir.path().join(format!("out{case}"));
        let args = [
            "run".as_ref(),
            scene.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
            "-q".as_ref(),
            "--steps".as_ref(),
            RUN_STEPS.as_ref(),
            "--max-memory".as_ref(),
            MAX_MEMORY.as_ref(),
        ];
        let Some((code, stderr)) = run_limited(&args, RUN_LIMIT, &dir.path().join("stderr.txt")) else {
            panic!("{}", failure(case, seed, &scene, "loam run did not finish its first steps"));
        };
        match code {
            Some(0) => {}
            Some(1) => failed += 1,
            other => panic!("{}", failure(case, seed, &scene, &format!("exit {other:?}: {stderr}"))),
        }
        for csv in ["history.csv", "points_final.csv"] {
            assert!(!non_finite_in(&out.join(csv)), "{}", failure(case, seed, &scene, &format!("NaN in {csv}")));
        }
    }
    println!("{runs} mutated scenes run in {:.1} s, {failed} stopped with an error", start.elapsed().as_secs_f64());
}
