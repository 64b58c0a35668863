#![doc = include_str!("../README.md")]
//! `thermokin-plot`: SVG plots of compensation runs and diagnoses, drawn into memory (plotters' SVG
//! backend, no system dependency); the front end writes them.

mod compensation;
mod diagnosis;

pub use compensation::{deviation_vs_time, structure};
pub use diagnosis::{heldout_per_effect, residuals};

/// A set of plots as a front end writes them: each file's name and its SVG.
pub type Plots = Vec<(&'static str, String)>;

/// A diagnosis' plots: `residuals.svg` ([`residuals`]) and `heldout-per-effect.svg`
/// ([`heldout_per_effect`]).
pub fn diagnosis_plots(report: &thermokin_diagnose::Report) -> Result<Plots, PlotError> {
    Ok(vec![("residuals.svg", residuals(report)?), ("heldout-per-effect.svg", heldout_per_effect(report)?)])
}

/// A compensation run's plots: `deviation-vs-time.svg` for a run over time ([`deviation_vs_time`]), and
/// `structure.svg` where a table deformed the robot ([`structure`], the deformation magnified 20 times).
pub fn run_plots(
    run: &thermokin_compensate::RunOutput,
    nominal: &thermokin_chain::Chain,
    deformed: Option<&thermokin_chain::Chain>,
) -> Result<Plots, PlotError> {
    let mut plots = Vec::new();
    if run.timed {
        plots.push(("deviation-vs-time.svg", deviation_vs_time(run)?));
    }
    if let Some(deformed) = deformed {
        plots.push(("structure.svg", structure(nominal, deformed, 20.0)?));
    }
    Ok(plots)
}

/// A plot that could not be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlotError {
    /// The drawing backend failed.
    #[error("drawing the plot: {0}")]
    Draw(String),
    /// The chain could not be evaluated.
    #[error(transparent)]
    Chain(#[from] thermokin_chain::ChainError),
}

impl<E: std::error::Error + Send + Sync> From<plotters::drawing::DrawingAreaErrorKind<E>> for PlotError {
    fn from(e: plotters::drawing::DrawingAreaErrorKind<E>) -> Self {
        PlotError::Draw(e.to_string())
    }
}

/// A tick label at its meaningful precision: three significant digits (`1e-9`, not
/// `9.999999999999999e-10`).
fn tick(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let text = format!("{v:.2e}");
    // 1.00e-9 → 1e-9, 2.50e1 → 2.5e1
    match text.split_once('e') {
        Some((mantissa, exponent)) => {
            let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
            match exponent {
                "0" => mantissa.to_string(),
                _ => format!("{mantissa}e{exponent}"),
            }
        }
        None => text,
    }
}
