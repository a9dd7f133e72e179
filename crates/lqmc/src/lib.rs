//! lqmc
