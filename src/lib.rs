//! loam facade
