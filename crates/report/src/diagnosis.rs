//! The diagnosis page: verdict and held-out figures, where the gap lies, the ladder of effects, each
//! effect's values, gross errors and refusals.

use std::fmt::Write;

use thermokin_chain::JointKind;
use thermokin_diagnose::{EffectReport, PoseRecord, Report, Stats};

use crate::html::{cell, chart, document, escape, figure, number, table, table_of_class, text_cell};
use crate::svg::{Axis, BarGroup, Bars, Chart, Colour, Layer};
use crate::{PageContext, drawn};

/// The page of `report` ([crate documentation](crate)).
pub fn diagnosis_page(report: &Report, context: &PageContext) -> String {
    let mut body = String::new();
    let title = format!("thermokin diagnosis — {} on {}", context.robot, context.data);
    let _ = write!(body, "<h1>{}</h1>", escape(&title));
    verdict(&mut body, report);
    heldout(&mut body, report, context);
    for w in &report.warnings {
        let _ = write!(body, "<p class=\"warn\">{}</p>", escape(w));
    }
    gap(&mut body, report);
    ladder(&mut body, report);
    effects(&mut body, report);
    gross_errors(&mut body, report);
    refusals(&mut body, report, context);
    identifiability(&mut body, report);
    let _ = write!(
        body,
        "<h2>How it was judged</h2><p>{}.</p><p><small>thermokin {} — every figure on this page is in the JSON report the same run writes (<code>--json</code>).</small></p>",
        escape(&report.validation),
        env!("CARGO_PKG_VERSION")
    );
    document(&title, &body)
}

/// The verdict, said first: the refusal when the diagnosis does not transfer.
fn verdict(out: &mut String, report: &Report) {
    if let Some(end) = &report.honest_end {
        let _ = write!(out, "<p class=\"refused\" data-figure=\"honest_end\"><strong>{}</strong></p>", escape(end));
    }
    let _ = write!(out, "<p class=\"verdict lead\" data-figure=\"verdict\">{}</p>", escape(&report.verdict));
}

/// A row of held-out statistics, each figure named `prefix.<statistic>` (median, p95 and max hidden on a
/// phone's width: the mean and RMS stay).
fn stats_row(label: &str, prefix: &str, s: &Stats) -> Vec<String> {
    vec![
        cell(label),
        figure(&format!("{prefix}.heldout_mean_mm"), s.heldout_mean_mm, 4),
        figure(&format!("{prefix}.heldout_median_mm"), s.heldout_median_mm, 4),
        figure(&format!("{prefix}.heldout_p95_mm"), s.heldout_p95_mm, 4),
        figure(&format!("{prefix}.heldout_rms_mm"), s.heldout_rms_mm, 4),
        figure(&format!("{prefix}.heldout_max_mm"), s.heldout_max_mm, 4),
    ]
}

/// The held-out figures in both protocols: nested (poses the selection never saw), the hold-out set as
/// exported (the training frame) and with its frame and probe refitted.
fn heldout(out: &mut String, report: &Report, context: &PageContext) {
    out.push_str("<h2>Held-out error</h2>");
    let header = ["mm", "mean", "median", "p95", "RMS", "max"];
    let mut rows = Vec::new();
    if let Some(n) = &report.nested {
        rows.push(stats_row("nested: nominal", "nested.nominal", &n.nominal));
        rows.push(stats_row("nested: chosen", "nested.selected", &n.selected));
    }
    if let Some(h) = &report.holdout {
        rows.push(stats_row("hold-out as exported: nominal", "holdout.same_frame.nominal", &h.same_frame.nominal));
        rows.push(stats_row("hold-out as exported: chosen", "holdout.same_frame.selected", &h.same_frame.selected));
        if !h.refitted.is_empty() {
            rows.push(stats_row("hold-out refitted: nominal", "holdout.nominal", &h.nominal));
            rows.push(stats_row("hold-out refitted: chosen", "holdout.selected", &h.selected));
        }
    }
    if rows.is_empty() {
        out.push_str("<p>No held-out figure: neither nested validation nor a hold-out set was asked for.</p>");
        return;
    }
    table_of_class(out, "hd", &header, &rows);
    let nested = report.nested.as_ref().map_or(String::new(), |n| {
        format!(
            "Nested: each of {} outer folds' poses scored by the selection run on the others, which never saw them. ",
            n.outer_folds
        )
    });
    let holdout = match (&report.holdout, &context.holdout) {
        (Some(h), Some(name)) => format!(
            "Hold-out <code>{}</code>: as exported — the model as <code>--export</code> writes it, nothing refitted (the use-test when both files share the tracker frame and probe); refitted — {} fitted again on the hold-out file, the effects kept.",
            escape(name),
            escape(&h.refitted.join(", "))
        ),
        _ => String::new(),
    };
    let _ = write!(out, "<p><small>{nested}{holdout}</small></p>");
}

/// The norm of a vector.
fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// Where the gap lies: residual vectors over the workspace, against each joint, over time, per fold.
fn gap(out: &mut String, report: &Report) {
    let poses = &report.poses;
    if poses.is_empty() {
        return;
    }
    out.push_str("<h2>Where the gap lies</h2>");
    let (shown, every) = drawn(poses.len());
    let of = if every > 1 {
        format!("one pose in {every} of the {} drawn", poses.len())
    } else {
        format!("all {} poses", poses.len())
    };
    // One arrow scale for before and after: the 95th percentile of the nominal residuals drawn as a tenth
    // of the workspace's larger extent.
    let mut sizes: Vec<f64> = poses.iter().map(|p| norm(&p.before_mm)).collect();
    sizes.sort_by(f64::total_cmp);
    let p95 = sizes[(sizes.len() * 95 / 100).min(sizes.len() - 1)].max(1e-9);
    let extent = (0..3)
        .map(|a| {
            let (lo, hi) =
                poses.iter().fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p.measured_mm[a]), h.max(p.measured_mm[a])));
            hi - lo
        })
        .fold(0.0, f64::max)
        .max(1.0);
    let scale = round_scale(0.1 * extent / p95);
    let view = |(a, b): (usize, usize), name: &str, after: bool| {
        let axis = |k: usize| {
            Axis::over(format!("{} [mm]", ["x", "y", "z"][k]), shown.iter().map(|&i| poses[i].measured_mm[k]))
        };
        let vector = |p: &PoseRecord| if after { p.after_mm } else { p.before_mm };
        let arrows = shown
            .iter()
            .map(|&i| {
                let p = &poses[i];
                ((p.measured_mm[a], p.measured_mm[b]), (scale * vector(p)[a], scale * vector(p)[b]))
            })
            .collect();
        let (colour, model) =
            if after { (Colour::Blue, "after: the final model") } else { (Colour::Grey, "before: the nominal model") };
        Chart {
            title: format!("{name}, {model}"),
            x: axis(a),
            y: axis(b),
            equal_scale: true,
            layers: vec![Layer::Arrows { arrows, colour, label: format!("residual ×{scale}") }],
        }
        .svg()
    };
    out.push_str("<h3>Residual vectors over the workspace</h3><div class=\"wide2\">");
    for (axes, name) in [((0, 1), "top view (x–y)"), ((0, 2), "side view (x–z)")] {
        for after in [false, true] {
            chart(
                out,
                &view(axes, name, after),
                &format!("Measured − predicted at each measured position, drawn ×{scale}; {of}."),
            );
        }
    }
    out.push_str("</div>");
    against_joints(out, report, &shown, &of);
    over_time(out, poses, &shown, &of);
    per_fold(out, report);
}

/// An arrow scale rounded to 1, 2 or 5 × 10ⁿ.
fn round_scale(s: f64) -> f64 {
    if !(s > 0.0 && s.is_finite()) {
        return 1.0;
    }
    let m = 10f64.powf(s.log10().floor());
    [5.0, 2.0, 1.0].iter().map(|k| k * m).find(|v| *v <= s).unwrap_or(m)
}

/// The residual's size against each joint's value, before and after.
fn against_joints(out: &mut String, report: &Report, shown: &[usize], of: &str) {
    let poses = &report.poses;
    let joints = poses.first().map_or(0, |p| p.joints.len());
    out.push_str("<h3>Residual against each joint</h3><div class=\"grid2\">");
    for j in 0..joints {
        let unit = match report.calibrated.joints().get(j).map(|x| x.kind) {
            Some(JointKind::Prismatic) => "mm",
            _ => "°",
        };
        let series = |after: bool| -> Vec<(f64, f64)> {
            shown
                .iter()
                .map(|&i| (poses[i].joints[j], norm(if after { &poses[i].after_mm } else { &poses[i].before_mm })))
                .collect()
        };
        let (before, after) = (series(false), series(true));
        let svg = Chart {
            title: format!("joint {}", j + 1),
            x: Axis::over(format!("joint {} [{unit}]", j + 1), before.iter().map(|p| p.0)),
            y: Axis::over("|residual| [mm]", before.iter().chain(&after).map(|p| p.1)).starting_at_zero(),
            equal_scale: false,
            layers: vec![
                Layer::Points { points: before, colour: Colour::Grey, label: "before".into() },
                Layer::Points { points: after, colour: Colour::Blue, label: "after".into() },
            ],
        }
        .svg();
        chart(out, &svg, &format!("Size of each pose's residual against joint {}'s value; {of}.", j + 1));
    }
    out.push_str("</div>");
}

/// The residual's size over time, when the measurements carry time.
fn over_time(out: &mut String, poses: &[PoseRecord], shown: &[usize], of: &str) {
    let (lo, hi) = poses.iter().fold((f64::MAX, f64::MIN), |(l, h), p| (l.min(p.time_min), h.max(p.time_min)));
    if hi <= lo || !hi.is_finite() {
        return;
    }
    let (unit, per) = if hi - lo > 1440.0 { ("h", 60.0) } else { ("min", 1.0) };
    let series = |after: bool| -> Vec<(f64, f64)> {
        shown
            .iter()
            .map(|&i| (poses[i].time_min / per, norm(if after { &poses[i].after_mm } else { &poses[i].before_mm })))
            .collect()
    };
    let (before, after) = (series(false), series(true));
    let svg = Chart {
        title: "over time".into(),
        x: Axis::over(format!("time [{unit}]"), before.iter().map(|p| p.0)),
        y: Axis::over("|residual| [mm]", before.iter().chain(&after).map(|p| p.1)).starting_at_zero(),
        equal_scale: false,
        layers: vec![
            Layer::Points { points: before, colour: Colour::Grey, label: "before".into() },
            Layer::Points { points: after, colour: Colour::Blue, label: "after".into() },
        ],
    }
    .svg();
    out.push_str("<h3>Over time</h3>");
    chart(out, &svg, &format!("Size of each pose's residual against the time it was measured; {of}."));
}

/// Each outer fold of the nested validation: the nominal and the chosen model on its test poses.
fn per_fold(out: &mut String, report: &Report) {
    let Some(n) = &report.nested else { return };
    let groups = n
        .folds
        .iter()
        .map(|f| BarGroup {
            label: format!("fold {} ({} poses)", f.fold, f.poses),
            values: vec![(f.nominal.heldout_rms_mm, None), (f.selected.heldout_rms_mm, None)],
        })
        .collect();
    let svg = Bars {
        title: "nested validation, fold by fold".into(),
        value_label: "held-out RMS [mm]".into(),
        series: vec![("nominal".into(), Colour::Grey), ("chosen there".into(), Colour::Blue)],
        groups,
    }
    .svg();
    out.push_str("<h3>Per outer fold</h3>");
    chart(out, &svg, "Each outer fold's test poses under the nominal model and the model its own selection chose.");
    let rows: Vec<Vec<String>> = n
        .folds
        .iter()
        .map(|f| {
            vec![
                cell(&format!("fold {}", f.fold)),
                cell(&f.poses.to_string()),
                number(Some(f.nominal.heldout_rms_mm), 4),
                number(Some(f.selected.heldout_rms_mm), 4),
                text_cell(&f.effects.join(", ")),
            ]
        })
        .collect();
    table(out, &["outer fold", "poses", "nominal RMS", "chosen RMS", "chose"], &rows);
}

/// The ladder: the held-out error as the effects joined, and with each left out.
fn ladder(out: &mut String, report: &Report) {
    out.push_str("<h2>The ladder of effects</h2>");
    let bars = |rows: &[thermokin_diagnose::TableRow], title: &str| {
        Bars {
            title: title.into(),
            value_label: "held-out RMS [mm] (whisker: median to 95th percentile)".into(),
            series: vec![("held-out RMS".into(), Colour::Blue)],
            groups: rows
                .iter()
                .map(|r| BarGroup {
                    label: r.model.clone(),
                    values: vec![(r.stats.heldout_rms_mm, Some((r.stats.heldout_median_mm, r.stats.heldout_p95_mm)))],
                })
                .collect(),
        }
        .svg()
    };
    chart(
        out,
        &bars(&report.additive, "as the effects joined"),
        "The selection's own folds (optimistic: these scores chose the effects).",
    );
    let row = |r: &thermokin_diagnose::TableRow| {
        vec![
            text_cell(&r.model),
            number(Some(r.stats.heldout_mean_mm), 4),
            number(Some(r.stats.heldout_rms_mm), 4),
            number(Some(r.stats.heldout_max_mm), 4),
        ]
    };
    table(out, &["model", "mean", "RMS", "max"], &report.additive.iter().map(row).collect::<Vec<_>>());
    if !report.leave_one_out.is_empty() {
        chart(
            out,
            &bars(&report.leave_one_out, "with each left out"),
            "The final model without each effect, on the same folds.",
        );
    }
}

/// Each effect's parameters with their standard deviations.
fn effects(out: &mut String, report: &Report) {
    out.push_str("<h2>Effects, main cause first</h2>");
    if report.effects.is_empty() {
        out.push_str("<p>No effect beyond the measurement frame and probe was chosen.</p>");
    }
    let one = |out: &mut String, e: &EffectReport| {
        let _ = write!(
            out,
            "<h3 data-effect=\"{}\">{}</h3><p><small>joined: {}; held-out RMS without it {:.4} mm{}</small></p>",
            escape(&e.label),
            escape(&e.label),
            escape(&e.joined),
            e.heldout_rms_without_mm,
            match (e.heldout_rms_before_mm, e.heldout_rms_after_mm) {
                (Some(b), Some(a)) => format!("; {b:.4} → {a:.4} mm as it joined"),
                _ => String::new(),
            }
        );
        let rows: Vec<Vec<String>> = e
            .parameters
            .iter()
            .map(|(name, v)| match &v.fixed {
                Some(why) => vec![cell(name), number(Some(v.value), 6), cell("fixed"), text_cell(why)],
                None => vec![cell(name), number(Some(v.value), 6), number(v.std, 6), cell("")],
            })
            .collect();
        table(out, &["parameter", "value", "σ", "why fixed"], &rows);
    };
    for e in &report.effects {
        one(out, e);
    }
    if !report.completed.is_empty() {
        out.push_str("<h2>Completed for use</h2><p>Not causes found: the joint rows and compliances a robot used in its training frame needs beside them; in every score above and in the export.</p>");
        for e in &report.completed {
            one(out, e);
        }
    }
    if report.shrinkage > 0.0 {
        let _ = write!(
            out,
            "<p>The export carries the fit shrunk toward the nominal robot: a prior worth {} rows of data per parameter.</p>",
            report.shrinkage
        );
    }
    let f = &report.frames;
    if let Some(r) = &f.registration {
        let _ = write!(
            out,
            "<p>Fitted registration (measurement frame ← base): {:.4}, {:.4}, {:.4} mm; {:.5}, {:.5}, {:.5}° (X-Y-Z Euler).</p>",
            r.position_mm[0],
            r.position_mm[1],
            r.position_mm[2],
            r.xyz_euler_deg[0],
            r.xyz_euler_deg[1],
            r.xyz_euler_deg[2]
        );
    }
    if let Some(t) = &f.tool_point_mm {
        let _ =
            write!(out, "<p>Fitted tool point in the robot's tip frame: {:.4}, {:.4}, {:.4} mm.</p>", t[0], t[1], t[2]);
    }
}

/// The gross errors the screen left out, by file line.
fn gross_errors(out: &mut String, report: &Report) {
    out.push_str("<h2>Gross errors</h2>");
    let s = &report.outlier_screen;
    let _ = write!(
        out,
        "<p>Threshold {:.4} mm against the screening model; residual scale {:.4} mm per axis. {}</p>",
        s.threshold_mm,
        s.scale_mm,
        if report.outliers.is_empty() {
            "None flagged.".to_string()
        } else if s.excluded {
            format!("{} flagged and left out of everything on this page.", report.outliers.len())
        } else {
            format!("{} flagged and kept (as asked).", report.outliers.len())
        }
    );
    if !report.outliers.is_empty() {
        let rows: Vec<Vec<String>> = report
            .outliers
            .iter()
            .map(|o| {
                vec![
                    cell(&o.line.map_or("—".into(), |l| l.to_string())),
                    cell(&o.measurement.to_string()),
                    number(Some(o.residual_mm), 4),
                ]
            })
            .collect();
        table(out, &["file line", "measurement", "residual [mm]"], &rows);
    }
    for c in &s.clusters {
        let _ = write!(out, "<p><strong>Not gross errors:</strong> {}</p>", escape(&c.sentence(s.threshold_mm)));
    }
}

/// Every refusal with what to measure, and the command that plans it.
fn refusals(out: &mut String, report: &Report, context: &PageContext) {
    let refused = &report.identifiability.not_identifiable;
    if refused.is_empty() {
        return;
    }
    out.push_str("<h2>Refused, and what to measure</h2>");
    let rows: Vec<Vec<String>> =
        refused.iter().map(|r| vec![cell(&r.effect), text_cell(&r.reason), text_cell(&r.remedy)]).collect();
    table(out, &["effect", "why", "what to do"], &rows);
    if let Some(cmd) = &context.next_poses {
        let _ = write!(out, "<p>The poses that pin them down: <code>{}</code></p>", escape(cmd));
    }
}

/// The final model's identifiability.
fn identifiability(out: &mut String, report: &Report) {
    let id = &report.identifiability;
    out.push_str("<h2>Identifiability</h2>");
    if let Some(o) = &id.observability {
        let _ = write!(
            out,
            "<p>{} parameters from {} residuals; condition number {:.3e}; O1 {:.3e}, O2 {:.3e}, O3 {:.3e}, O4 {:.3e}, O5 {:.3e}.</p>",
            o.parameters, o.rows, o.condition_number, o.o1, o.o2, o.o3, o.o4, o.o5
        );
    }
    if !id.fixed.is_empty() {
        let _ = write!(out, "<details><summary>{} parameters fixed as not identifiable</summary>", id.fixed.len());
        let rows: Vec<Vec<String>> = id.fixed.iter().map(|f| vec![cell(&f.parameter), text_cell(&f.reason)]).collect();
        table(out, &["parameter", "why"], &rows);
        out.push_str("</details>");
    }
    if !id.correlated.is_empty() {
        let rows: Vec<Vec<String>> =
            id.correlated.iter().map(|c| vec![cell(&c.a), cell(&c.b), number(Some(c.correlation), 4)]).collect();
        out.push_str("<h3>Nearly unidentifiable combinations</h3>");
        table(out, &["parameter", "parameter", "correlation"], &rows);
    }
}
