#![doc = include_str!("../README.md")]
//! `thermokin-report`: a diagnosis and a measurement plan as one self-contained HTML page — the verdict
//! and the held-out figures first, then where the gap lies, drawn as inline SVG from the report's own
//! numbers. Nothing on the page is fetched: no script, no font, no style sheet from elsewhere; it opens
//! offline and reads on a laptop and on a phone. The front ends write the page ([`diagnosis_page`],
//! [`plan_page`]); a test renders it in a real browser.
//!
//! ```
//! use thermokin_chain::Robot;
//! use thermokin_diagnose::{Config, HiddenEffect, SimulationConfig, diagnose, simulate};
//! use thermokin_identify::{Effect, JointIndex};
//! use thermokin_report::{PageContext, diagnosis_page};
//!
//! let robot = Robot::new("IRB 140", thermokin_testdata::irb140_table9());
//! let offset = Effect::JointOffset(JointIndex::of(&robot, 1)?);
//! let hidden = [HiddenEffect { effect: offset, values: vec![0.05f64.to_radians()] }];
//! let data = simulate(&robot, &hidden, &SimulationConfig { poses: 120, ..SimulationConfig::default() })?;
//! let report = diagnose(&robot, &data, None, &Config::default())?;
//! let page = diagnosis_page(&report, &PageContext::new("IRB 140", "simulated.csv"));
//! assert!(page.starts_with("<!DOCTYPE html>") && page.contains("joint_offset[2]"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod diagnosis;
mod html;
mod plan;
mod svg;

pub use diagnosis::diagnosis_page;
pub use plan::plan_page;

/// What the page says it is of, beside the report: the names a user gave.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PageContext {
    /// The robot, as named (a file's path, a robot's name).
    pub robot: String,
    /// The measurements (or the candidates, for a plan), as named.
    pub data: String,
    /// The hold-out set, as named, when one was given.
    pub holdout: Option<String>,
    /// The command that plans the next poses, where the diagnosis refused effects for what its poses
    /// cover (a front end writes it in its own words).
    pub next_poses: Option<String>,
}

impl PageContext {
    /// A page of `robot` on `data`.
    pub fn new(robot: impl Into<String>, data: impl Into<String>) -> Self {
        Self { robot: robot.into(), data: data.into(), ..Self::default() }
    }
}

/// At most this many poses are drawn in a scatter or arrow chart: a week of 12,000 poses would make a
/// page of tens of megabytes that a phone renders slowly; every `k`-th pose is drawn and the caption says
/// how many.
pub(crate) const MOST_DRAWN: usize = 1500;

/// Every `k`-th index of `0..n`, at most [`MOST_DRAWN`] of them, and `k`.
pub(crate) fn drawn(n: usize) -> (Vec<usize>, usize) {
    let k = n.div_ceil(MOST_DRAWN).max(1);
    ((0..n).step_by(k).collect(), k)
}
