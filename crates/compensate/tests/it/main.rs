//! Integration tests of the compensation runs: the paper's two case studies as golden assertions.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail; case tables are tuples.

mod calibrated;
mod case_studies;
mod stream;
