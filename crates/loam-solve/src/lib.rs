//! loam-solve
