//! loam-points
