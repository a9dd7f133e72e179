//! The correctness harness (placeholder while being written).
