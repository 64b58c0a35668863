//! Integration tests of the readers: the bundled IRB 140 and its DH tables, the authors' files, bad input.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail; case tables are tuples.

mod bad_input;
mod calibrated_robot;
mod fuzz_replay;
mod irb140;
mod orientation;
mod readers;
