//! `thermokin-plot`: SVG plots of compensation runs and diagnoses, drawn into memory (plotters' SVG
//! backend, no system dependency); the front end writes them.

mod compensation;
mod diagnosis;

pub use compensation::{deviation_vs_time, structure};
pub use diagnosis::{heldout_per_effect, residuals};

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
