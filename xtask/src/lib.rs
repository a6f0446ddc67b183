//! The parts of xtask that need no analysis, kept in a library so that their unit tests
//! build without the binary: `cargo test` would otherwise compile the whole verification
//! program a second time, as a test harness, beside the binary `cargo xtask` runs.

pub mod docs_tables;
