//! pathspace
