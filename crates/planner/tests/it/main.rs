//! The measurement planner's integration tests: its claims checked against simulated truths made by code
//! other than the planner's model (the chain's FK, the robot model of `thermokin-deform`), and on real
//! tracker data through the diagnosis.
#![allow(clippy::unwrap_used, clippy::panic, missing_docs)] // Tests unwrap and panic to fail.

mod plan;
mod real;
mod region;
mod simulated;
