//! Explicit MPM (placeholder; being written).
