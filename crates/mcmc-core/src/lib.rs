//! mcmc-core
