//! The plan page: what the planned poses give against random ones, where they are, in which order, and
//! what they still cannot pin down.

use std::fmt::Write;

use thermokin_planner::Plan;

use crate::html::{cell, chart, document, escape, figure, number, table, text_cell};
use crate::svg::{Axis, BarGroup, Bars, Chart, Colour, Layer};
use crate::{PageContext, drawn};

/// The page of `plan` ([crate documentation](crate)).
pub fn plan_page(plan: &Plan, context: &PageContext) -> String {
    let mut body = String::new();
    let title = format!("thermokin plan — {} poses for {}", plan.poses.len(), context.robot);
    let _ = write!(body, "<h1>{}</h1>", escape(&title));
    let _ = write!(
        body,
        "<p class=\"verdict lead\">{} poses chosen from {} candidates ({}){}, {} criterion, at a tracker noise of {} mm per axis.</p>",
        plan.poses.len(),
        plan.candidates,
        escape(&context.data),
        if plan.measured > 0 { format!(" beside {} poses already measured", plan.measured) } else { String::new() },
        match plan.criterion {
            thermokin_planner::Criterion::Parameters => "the D-optimal (parameters)",
            thermokin_planner::Criterion::Prediction => "the I-optimal (prediction)",
        },
        plan.noise_mm
    );
    said(&mut body, plan);
    comparison(&mut body, plan);
    workspace(&mut body, plan);
    coverage(&mut body, plan);
    poses(&mut body, plan);
    parameters(&mut body, plan);
    let _ = write!(
        body,
        "<p><small>thermokin {} — every figure on this page is in the JSON the same run writes (<code>--json</code>).</small></p>",
        env!("CARGO_PKG_VERSION")
    );
    document(&title, &body)
}

/// What the plan says before its tables: where the poses of use leave the candidates' arcs, and why an
/// automatic count stopped where it did.
fn said(out: &mut String, plan: &Plan) {
    if !plan.beyond_candidates.is_empty() {
        let joints: Vec<String> = plan.beyond_candidates.iter().map(ToString::to_string).collect();
        let _ = write!(
            out,
            "<p class=\"warn\">The poses of use leave the candidates' arcs — {}: there the model is extrapolated, and no variance bounds its error.</p>",
            escape(&joints.join(", "))
        );
        let p = &plan.promise;
        if p.planned_at_nearest > 0 {
            let as_given = p.planned_as_given_rms_mm.map_or("nothing finite".into(), |r| format!("{r:.4} mm"));
            let _ = write!(
                out,
                "<p>{} of the {} poses of use reach beyond those arcs: the plan is made, and its promise stated, at the nearest candidate to each, where a measurement can check the prediction (<code>--beyond-arcs as-given</code> plans for them as given). At the poses as given, the model planned for taken as the robot there, the planned poses would promise {}.</p>",
                p.planned_at_nearest,
                p.poses_of_use,
                escape(&as_given)
            );
        }
    }
    if let Some(c) = &plan.count {
        let why = match c.stopped {
            Some([gain, resolution]) => format!(
                "one more would lower the predicted held-out RMS by {gain:.2e} mm, below the {resolution:.2e} mm a test at the poses of use can show"
            ),
            None => format!("the most allowed ({})", c.at_most),
        };
        let _ = write!(out, "<p>{} poses: {}.</p>", plan.poses.len(), escape(&why));
    }
}

/// The plan against random draws of the same pool.
fn comparison(out: &mut String, plan: &Plan) {
    let c = &plan.comparison;
    out.push_str("<h2>Against random poses</h2>");
    let promise = &plan.promise;
    let at = match promise.region {
        thermokin_planner::PosesOfUse::Given if promise.planned_at_nearest > 0 => format!(
            "the {} poses of use ({} at their nearest candidate)",
            promise.poses_of_use, promise.planned_at_nearest
        ),
        thermokin_planner::PosesOfUse::Given => format!("the {} poses of use", promise.poses_of_use),
        thermokin_planner::PosesOfUse::Candidates => format!("the {} candidates", promise.poses_of_use),
    };
    let mut rows = vec![vec![
        cell(&format!("predicted held-out RMS at {at} [mm]")),
        figure("promise.planned_rms_mm", promise.planned_rms_mm, 4),
        match promise.random_rms_mm {
            Some(r) => figure("promise.random_rms_mm", r, 4),
            None => cell("not identifiable"),
        },
    ]];
    rows.push(vec![
        cell("D-criterion log det"),
        figure("comparison.planned_criterion", c.planned_criterion, 3),
        figure("comparison.random_criterion", c.random_criterion, 3),
    ]);
    if let (Some(p), Some(r)) = (&c.planned, &c.random) {
        rows.push(vec![
            cell("condition number"),
            figure("comparison.planned.condition_number", p.condition_number, 1),
            figure("comparison.random.condition_number", r.condition_number, 1),
        ]);
        for (name, a, b) in [("O1", p.o1, r.o1), ("O3", p.o3, r.o3)] {
            rows.push(vec![cell(name), number(Some(a), 6), number(Some(b), 6)]);
        }
    }
    table(out, &["", "planned", &format!("random (median of {})", c.random_draws)], &rows);
}

/// The planned poses over the workspace, joined in measuring order.
fn workspace(out: &mut String, plan: &Plan) {
    if plan.poses.is_empty() {
        return;
    }
    let (shown, _) = drawn(plan.poses.len());
    let p: Vec<[f64; 3]> = shown.iter().map(|&i| plan.poses[i].nominal_position_mm).collect();
    out.push_str("<h2>Where the poses are</h2><div class=\"grid2\">");
    for ((a, b), name) in [((0, 1), "top view (x–y)"), ((0, 2), "side view (x–z)")] {
        let axis = |k: usize| Axis::over(format!("{} [mm]", ["x", "y", "z"][k]), p.iter().map(|v| v[k]));
        let path = p.windows(2).map(|w| ((w[0][a], w[0][b]), (w[1][a] - w[0][a], w[1][b] - w[0][b]))).collect();
        let svg = Chart {
            title: format!("planned poses, {name}"),
            x: axis(a),
            y: axis(b),
            equal_scale: true,
            layers: vec![
                Layer::Arrows { arrows: path, colour: Colour::Grey, label: "measuring order".into() },
                Layer::Points {
                    points: p.iter().map(|v| (v[a], v[b])).collect(),
                    colour: Colour::Blue,
                    label: "pose".into(),
                },
            ],
        }
        .svg();
        chart(
            out,
            &svg,
            "Where the tracker should see the tool (nominal robot, base frame), joined in the order to measure.",
        );
    }
    out.push_str("</div>");
}

/// Each joint's arc over the planned and measured poses.
fn coverage(out: &mut String, plan: &Plan) {
    if plan.coverage.is_empty() {
        return;
    }
    let svg = Bars {
        title: "joint coverage".into(),
        value_label: "fraction of the joint's travel covered".into(),
        series: vec![("covered".into(), Colour::Blue)],
        groups: plan
            .coverage
            .iter()
            .map(|c| BarGroup {
                label: format!("joint {} ({:.0} … {:.0})", c.joint, c.arc[0], c.arc[1]),
                values: vec![(c.fraction_of_travel, None)],
            })
            .collect(),
    }
    .svg();
    out.push_str("<h2>What the poses cover</h2>");
    chart(out, &svg, "The arc each joint covers over the planned (and measured) poses, as a fraction of its travel.");
    if !plan.left_out.is_empty() {
        let rows: Vec<Vec<String>> =
            plan.left_out.iter().map(|l| vec![cell(&l.effect), text_cell(&l.reason)]).collect();
        out.push_str("<h3>Not planned for</h3>");
        table(out, &["effect", "why"], &rows);
    }
}

/// The poses in measuring order.
fn poses(out: &mut String, plan: &Plan) {
    out.push_str("<h2>The poses, in measuring order</h2>");
    let joints = plan.poses.first().map_or(0, |p| p.joints.len());
    let mut header: Vec<String> = vec!["#".into(), "line".into()];
    header.extend((1..=joints).map(|j| format!("q{j}")));
    header.extend(["x [mm]".into(), "y [mm]".into(), "z [mm]".into(), "helps".into()]);
    let rows: Vec<Vec<String>> = plan
        .poses
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let mut row = vec![cell(&(k + 1).to_string()), cell(&p.line.map_or("—".into(), |l| l.to_string()))];
            row.extend(p.joints.iter().map(|q| number(Some(*q), 2)));
            row.extend(p.nominal_position_mm.iter().map(|v| number(Some(*v), 1)));
            row.push(text_cell(&p.helps.join(", ")));
            row
        })
        .collect();
    let header: Vec<&str> = header.iter().map(String::as_str).collect();
    table(out, &header, &rows);
}

/// Each parameter's predicted standard deviation, and what stays unidentifiable.
fn parameters(out: &mut String, plan: &Plan) {
    out.push_str("<h2>Predicted precision</h2>");
    let rows: Vec<Vec<String>> =
        plan.parameters.iter().map(|p| vec![cell(&p.parameter), number(p.planned, 6), number(p.random, 6)]).collect();
    table(out, &["parameter", "σ planned", "σ random (median)"], &rows);
    for (list, what) in [
        (&plan.not_identifiable, "Not identifiable from the planned poses"),
        (&plan.never_identifiable, "Not identifiable from any choice of these candidates"),
    ] {
        if !list.is_empty() {
            let _ = write!(out, "<h3>{what}</h3>");
            let rows: Vec<Vec<String>> = list.iter().map(|f| vec![cell(&f.parameter), text_cell(&f.reason)]).collect();
            table(out, &["parameter", "why"], &rows);
        }
    }
}
