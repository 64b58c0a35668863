//! Integration tests of URDF import and export on the real URDFs in `fixtures/urdf`.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail.

mod bad_urdf;
mod export_rules;
mod real_robots;
