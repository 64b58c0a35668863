//! Integration tests of the kinematic core: conventions, conversions, Jacobians.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail; case tables are tuples.

mod conversions;
mod gravity;
mod jacobians;
mod rotation_log;
mod support;
