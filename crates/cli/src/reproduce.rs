//! `thermokin reproduce-paper`: a thin caller of [`thermokin_paper::reproduce`] — it shows progress,
//! draws the plots, writes the report and the measured numbers, and checks them against a golden file.

use std::time::Instant;

use thermokin_paper::{Inputs, check_file, reproduce};

use crate::args::ReproduceArgs;
use crate::input::progress_bar;
use crate::{Failure, exit};

fn paper(e: thermokin_paper::PaperError) -> Failure {
    match e {
        thermokin_paper::PaperError::Io(_) | thermokin_paper::PaperError::Fixture { .. } => Failure::input(e),
        other => Failure::internal(other),
    }
}

pub fn run(a: ReproduceArgs) -> Result<u8, Failure> {
    let started = Instant::now();
    let inputs = Inputs {
        fixtures: a.fixtures.clone(),
        robot: a.robot.clone(),
        scene_robot: a.scene_robot.clone(),
        authors: a.authors.clone(),
    };
    let bar = progress_bar(201, "transient case");
    let r = reproduce(&inputs, |done, total| bar.set_position(done as u64, total as u64)).map_err(paper)?;
    bar.finish();

    if let Some(dir) = &a.plot {
        let plots = thermokin_plot::deviation_vs_time(&r.transient_run).and_then(|deviation| {
            Ok(vec![
                ("transient-deviation.svg", deviation),
                ("figure15-structure.svg", thermokin_plot::structure(&r.scene, &r.deformed, 10.0)?),
            ])
        });
        crate::out::save_plots(dir, plots)?;
    }
    if let Some(p) = &a.report {
        crate::out::save(p, r.report)?;
    }
    if let Some(p) = &a.json {
        let text = serde_json::to_string_pretty(&r.measurements.golden_json()).map_err(Failure::internal)?;
        crate::out::save(p, text)?;
    }
    say!("{}", r.headline.text());
    say!("({:.2} s)", started.elapsed().as_secs_f64());
    let mut code = exit::OK;
    if let Some(golden) = &a.check {
        let drift = check_file(golden, &r.measurements.golden_json()).map_err(paper)?;
        if drift.is_empty() {
            say!("check: no drift against {}", golden.display());
        } else {
            for d in &drift {
                eprintln!("drift: {d}");
            }
            code = exit::DRIFT;
        }
    }
    if r.static_run.summary.failures + r.transient_run.summary.failures > 0 {
        code = code.max(exit::PARTIAL);
    }
    Ok(code)
}
