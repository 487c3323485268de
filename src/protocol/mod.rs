//! The sans-IO protocol core.

pub mod v2;
