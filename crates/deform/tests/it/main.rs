//! Integration tests of the error-parameter model.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail; case tables are tuples.

mod model;
mod profiles;
