//! loam-io

pub mod output;
