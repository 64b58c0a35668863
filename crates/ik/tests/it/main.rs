//! Integration tests of the IK solver on the bundled IRB 140, nominal and deformed.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail; case tables are tuples.

mod analytic;
mod half_turn;
mod solve;
