//! Integration tests of the `thermokin` binary: outputs, exit statuses, bad input, atomic writes.
#![allow(clippy::unwrap_used, clippy::panic, clippy::type_complexity, missing_docs)] // Tests unwrap and panic to fail; case tables are tuples.

mod accelerometers;
mod bad_inputs;
mod branches;
mod citizen;
mod cli;
mod edges;
mod guide;
mod page;
mod plan;
mod real_data;
mod warmup_loop;
