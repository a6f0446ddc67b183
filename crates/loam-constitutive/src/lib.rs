//! loam-constitutive
