//! Plots of a compensation run: the largest error per time step before and after, and the structure
//! nominal and deformed (the paper's Figure 15).

use plotters::prelude::*;
use thermokin_chain::Chain;
use thermokin_compensate::RunOutput;

use crate::{PlotError, tick};

/// Largest error per time step, before and after compensation, on a log scale.
pub fn deviation_vs_time(run: &RunOutput) -> Result<String, PlotError> {
    let mut times: Vec<f64> = run.rows.iter().map(|r| r.time_min).collect();
    times.dedup();
    let per_time = |f: &dyn Fn(&thermokin_compensate::TargetResult) -> f64| -> Vec<(f64, f64)> {
        times
            .iter()
            .map(|&t| {
                let m = run.rows.iter().filter(|r| r.time_min == t).map(f).fold(0.0, f64::max);
                (t, m.max(1e-12))
            })
            .collect()
    };
    let after = per_time(&|r| nalgebra::Vector3::from(r.position_deviation_mm).norm());
    let before = per_time(&|r| r.uncompensated_error_mm);
    let t_max = times.last().copied().unwrap_or(1.0).max(1.0);
    let y_max = before.iter().map(|p| p.1).fold(1e-3, f64::max) * 2.0;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 520)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption("Largest TCP position error per time step", ("sans-serif", 22))
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..t_max, (1e-12..y_max).log_scale())?;
        chart
            .configure_mesh()
            .x_desc("operating time [min]")
            .y_desc("error [mm]")
            .y_label_formatter(&|v| tick(*v))
            .draw()?;
        chart
            .draw_series(LineSeries::new(before, RED.stroke_width(2)))?
            .label("uncompensated program on the deformed robot")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        chart
            .draw_series(LineSeries::new(after, BLUE.stroke_width(2)))?
            .label("compensated (IK on the deformed model)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        root.present()?;
    }
    Ok(svg)
}

/// The structure at home, nominal and deformed, projected on the X–Z plane, the deformation magnified
/// `magnify` times (the paper's Figure 15).
pub fn structure(nominal: &Chain, deformed: &Chain, magnify: f64) -> Result<String, PlotError> {
    let zeros = vec![0.0; nominal.dof()];
    let points = |c: &Chain| -> Result<Vec<(f64, f64)>, PlotError> {
        let mut pts = vec![(0.0, 0.0)];
        for f in c.joint_frames(&zeros)? {
            pts.push((f.translation.vector.x, f.translation.vector.z));
        }
        Ok(pts)
    };
    let a = points(nominal)?;
    let b: Vec<(f64, f64)> = points(deformed)?
        .iter()
        .zip(&a)
        .map(|(d, n)| (n.0 + magnify * (d.0 - n.0), n.1 + magnify * (d.1 - n.1)))
        .collect();
    let all = a.iter().chain(&b);
    let (mut x0, mut x1, mut z0, mut z1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in all {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        z0 = z0.min(p.1);
        z1 = z1.max(p.1);
    }
    let pad = 0.1 * (x1 - x0).max(z1 - z0).max(1.0);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 700)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("Nominal and deformed structure at home (deformation ×{magnify})"), ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d((x0 - pad)..(x1 + pad), (z0 - pad)..(z1 + pad))?;
        chart.configure_mesh().x_desc("X [mm]").y_desc("Z [mm]").draw()?;
        chart
            .draw_series(LineSeries::new(a.clone(), BLACK.stroke_width(3)))?
            .label("nominal")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        chart.draw_series(a.iter().map(|p| Circle::new(*p, 4, BLACK.filled())))?;
        chart
            .draw_series(LineSeries::new(b.clone(), RED.stroke_width(2)))?
            .label("deformed")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        chart.draw_series(b.iter().map(|p| Circle::new(*p, 4, RED.filled())))?;
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
        root.present()?;
    }
    Ok(svg)
}
