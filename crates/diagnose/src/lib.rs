#![doc = include_str!("../README.md")]
//! `thermokin-diagnose`: the sim-to-real diagnosis — where the model and the measured robot disagree,
//! which unmodelled effect causes it, and how far the gap shrinks once that effect is added, always
//! judged on held-out data.
//!
//! The model of effects, its fit and identifiability are `thermokin-identify`'s. The diagnosis stacks,
//! from the bottom (ARCHITECTURE.md lists the layers; `cargo xtask deps` checks that no module uses one
//! above it): its settings ([`Config`]), errors and statistics; the report's types and the measurements
//! as read (in their own order, their sensors and accelerometers); folds and physical sense; the fit and
//! held-out scoring of a model, with the gate that accepts a gain only beyond its own uncertainty; what
//! scoring judges — a drift's law, a step of the frame, eligibility, the selection's state, the
//! linearised screen; the screen for gross errors, which decides the measurements everything above works
//! on; the prior, the completion and the coupled pairs; the selection's phases (forward, backward,
//! parsimony, extrapolation) and the tables of its choice; the validation of the whole procedure on data
//! it never saw (nested, a hold-out set), the warnings and the verdict; [`diagnose`] assembling the
//! [`Report`], which renders itself ([`Report::text`]).

mod at_use;
mod backward;
mod branches;
mod canonical;
mod clusters;
mod completion;
mod config;
mod diagnosis;
mod drifts;
mod eligibility;
mod error;
mod extrapolation;
mod folds;
mod forward;
mod linearised;
mod masses;
mod outliers;
mod pairs;
mod parsimony;
mod plausibility;
mod profile;
mod regions;
mod render;
mod report;
mod scoring;
mod screen;
mod select;
mod selection;
mod sensors;
mod shrinkage;
mod simulate;
mod stats;
mod steps;
mod tables;
mod tilts;
mod validation;
mod verdict;

pub use config::{
    Accelerometer, Completion, Config, Eligibility, Extrapolation, Fitted, FoldGrouping, Masses, Outliers,
    Plausibility, Promised, Screen, Shrinkage, Validation,
};
pub use diagnosis::{Progress, diagnose, diagnose_profiled, diagnose_with_progress};
pub use error::DiagnoseError;
pub use outliers::MIN_REDUNDANCY;
pub use profile::{Phase, PhaseCost, Profile};
pub use render::ReportText;
pub use report::{
    Along, AtUse, Breakdown, Cluster, EffectReport, FittedFrames, HoldoutPair, HoldoutStats, Identifiability, Nested,
    OuterFold, Outlier, OutlierScreen, ParameterValue, PoseHeldOut, PoseRecord, PoseReport, Refusal, Report,
    ScaleSource, ScreenCompliance, ScreenModel, Skipped, TableRow,
};
pub use sensors::not_sensors;
pub use simulate::{HiddenEffect, SimulationConfig, simulate};
pub use stats::FALSE_ALARM;
pub use stats::Stats;
pub use tilts::declared_accelerometers;
pub use validation::{Transfer, evaluate};
