#![doc = include_str!("../README.md")]
//! `thermokin-paper`: the paper's case studies as values, compared with the authors' own files.
//!
//! This crate holds what is specific to reproducing *the paper* rather than to compensating a user's
//! robot: [`reproduce`], both case studies rerun and compared side by side; [`scene`], the authors' CoppeliaSim scene identified from their files and replayed —
//! why FK of their published static angles sat 0.45 mm from their published coordinates, and which
//! explanations the data confirm or reject; and [`mod@print`], the printed result tables as data, compared
//! with the authors' files and with their angles on the replayed scene.
//!
//! Every number here is computed from the authors' files (`fixtures/paper/authors/`) and Table 9; none
//! is transcribed from our own earlier output.

mod measure;
pub mod print;
mod render;
mod reproduce;
pub mod scene;

pub use measure::{
    AuthorsComparison, FkResidual, Measurements, PrintComparison, PrintRow, SceneReplay, Table14Row, Table16Comparison,
    Table16Row,
};
pub use reproduce::{Headline, Inputs, Reproduction, check, check_file, reproduce};

pub use scene::{
    Hypothesis, Residuals, SCENE_RANK_CUTOFF, SinglePrecisionEvidence, TransientCandidate, Verdict,
    identify_scene_geometry, identify_tool_point, residuals, scene_chain, single_precision_evidence, static_hypotheses,
    transient_candidates,
};

/// Errors of the reproduction.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PaperError {
    /// The kinematic model could not be built or evaluated.
    #[error(transparent)]
    Chain(#[from] thermokin_chain::ChainError),
    /// The deformation could not be applied.
    #[error(transparent)]
    Deform(#[from] thermokin_deform::DeformError),
    /// A file could not be read.
    #[error(transparent)]
    Io(#[from] thermokin_io::IoError),
    /// A compensation run could not be set up.
    #[error(transparent)]
    Compensate(#[from] thermokin_compensate::CompensateError),
    /// The report could not be formatted (writing to a `String` does not fail; a formatting trait
    /// implementation can).
    #[error("the report could not be formatted")]
    Format(#[from] std::fmt::Error),
    /// A transcribed fixture is malformed.
    #[error("{path}:{line}: {message}", path = path.display())]
    Fixture {
        /// The file.
        path: std::path::PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The authors' rows do not fit the robot.
    #[error("{what}: expected {expected} rows or joints, got {got}")]
    Shape {
        /// Which data.
        what: &'static str,
        /// Expected count.
        expected: usize,
        /// Count found.
        got: usize,
    },
}
