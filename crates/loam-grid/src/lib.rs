//! loam-grid
