//! Plots of a diagnosis: the residual of every measurement before and after, and the held-out error as
//! effects are added.

use plotters::prelude::*;
use thermokin_diagnose::Report;

use crate::PlotError;

/// Each measurement's position residual, nominal model and with the effects found.
pub fn residuals(r: &Report) -> Result<String, PlotError> {
    let before = &r.residuals_before.per_measurement_mm;
    let after = &r.residuals_after.per_measurement_mm;
    let y_max = before.iter().chain(after).copied().fold(1e-6, f64::max) * 1.1;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 500)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Position residual per measurement, before and after", ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0usize..before.len().max(1), 0.0..y_max)?;
        chart.configure_mesh().x_desc("measurement").y_desc("|residual| [mm]").draw()?;
        chart
            .draw_series(before.iter().enumerate().map(|(i, v)| Circle::new((i, *v), 3, RED.filled())))?
            .label("nominal model")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, RED.filled()));
        chart
            .draw_series(after.iter().enumerate().map(|(i, v)| Circle::new((i, *v), 3, BLUE.filled())))?
            .label("with the effects found")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, BLUE.filled()));
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        root.present()?;
    }
    Ok(svg)
}

/// The held-out RMS of the additive table, model by model.
pub fn heldout_per_effect(r: &Report) -> Result<String, PlotError> {
    let rows = &r.additive;
    let y_max = rows.iter().map(|x| x.stats.heldout_rms_mm).fold(1e-6, f64::max) * 1.1;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 500)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Held-out RMS as effects are added", ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(60)
            .y_label_area_size(60)
            .build_cartesian_2d((0..rows.len()).into_segmented(), 0.0..y_max)?;
        chart
            .configure_mesh()
            .y_desc("held-out RMS [mm]")
            .x_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => rows.get(*i).map_or(String::new(), |r| r.model.clone()),
                _ => String::new(),
            })
            .draw()?;
        chart.draw_series(
            Histogram::vertical(&chart)
                .style(BLUE.mix(0.6).filled())
                .data(rows.iter().enumerate().map(|(i, r)| (i, r.stats.heldout_rms_mm))),
        )?;
        root.present()?;
    }
    Ok(svg)
}
