//! chainlight
