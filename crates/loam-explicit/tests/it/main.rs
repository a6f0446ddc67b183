//! The explicit crate's integration tests in one binary: each test binary builds the
//! solver's generic code again, so one binary instead of two halves that work in
//! `cargo test`.

mod common;
mod contact;
mod motion;
