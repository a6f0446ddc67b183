//! loam-implicit
