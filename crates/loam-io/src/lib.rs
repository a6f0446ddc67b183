//! loam-io
