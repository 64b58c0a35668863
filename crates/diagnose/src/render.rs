//! The diagnosis report as text: what `thermokin diagnose` prints, produced here so that every front end
//! (the CLI, the Python binding) shows the same words and figures ([`Report::text`]). The JSON form is
//! the report's `serde` serialisation.

use std::fmt;

use crate::report::{Report, ScaleSource, ScreenCompliance, ScreenModel};
use crate::stats::Stats;

/// The text rendering of a report ([`Report::text`]): held-out errors (nested, hold-out set, the
/// selection's own), the effects with their parameters, frames, verdict, where the residuals lie, and
/// identifiability.
pub struct ReportText<'a>(&'a Report);

impl Report {
    /// The report as the text `thermokin diagnose` prints (`format!("{}", report.text())`).
    pub fn text(&self) -> ReportText<'_> {
        ReportText(self)
    }
}

impl fmt::Display for ReportText<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        render(self.0, f)
    }
}

fn render(r: &Report, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    if let Some(why) = &r.honest_end {
        writeln!(f, "NOT BETTER THAN NOMINAL: {why}\n")?;
    }
    for w in &r.warnings {
        writeln!(f, "warning: {w}")?;
    }
    if let Some(lever) = r.orientation_lever_mm {
        writeln!(
            f,
            "6-D measurements: orientations fitted with positions; every error below is √(|Δp|² + ({lever} mm · |δφ|)²), {lever} mm the orientation lever"
        )?;
    }
    gross_errors(r, f)?;
    heldout(r, f)?;
    effects(r, f)?;
    frames_and_verdict(r, f)?;
    identifiability(r, f)
}

/// The screen for gross errors: what it judged against, and every flagged measurement by its line.
fn gross_errors(r: &Report, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let s = &r.outlier_screen;
    let geometry = match s.compliance {
        ScreenCompliance::FileMasses => "the full geometry with gravity compliance",
        ScreenCompliance::Lumped => {
            "the full geometry with gravity compliance, its loads lumped and fitted (no masses from the robot file)"
        }
        ScreenCompliance::NotLoaded => "the full geometry (no gravity compliance: gravity loads no joint here)",
        ScreenCompliance::TooFewPoses => {
            "the full geometry (no gravity compliance: the robot file gives no masses, and the poses are too few to fit its loads lumped)"
        }
    };
    let model = match s.model {
        ScreenModel::FullGeometry => geometry.to_string(),
        ScreenModel::ShrunkGeometry { effective_parameters, prior_rows } => format!(
            "{geometry}, shrunk toward the nominal robot to {effective_parameters:.1} effective parameters (a prior worth {prior_rows:.2} rows of data per parameter: too few poses for it unshrunk)"
        ),
        ScreenModel::FrameOnly => {
            "the registration and tool freedoms alone (too few poses for the full geometry, even shrunk)".to_string()
        }
    };
    let scale = match s.scale_from {
        ScaleSource::StatedNoise => {
            format!("{:.4} mm per axis (the stated noise; the residuals' is smaller)", s.scale_mm)
        }
        ScaleSource::Residuals => {
            format!("{:.4} mm per axis (the residuals' robust scale, estimated from the data)", s.scale_mm)
        }
    };
    let fate = if s.excluded { "left out of everything below" } else { "kept in the data (as asked)" };
    match r.outliers.len() {
        0 => writeln!(f, "gross errors: none beyond {:.4} mm against {model}; scale {scale}", s.threshold_mm),
        n => {
            let poses = if n == 1 { "measurement" } else { "measurements" };
            writeln!(
                f,
                "gross errors: {n} {poses} beyond {:.4} mm against {model}, {fate}; scale {scale}:",
                s.threshold_mm
            )?;
            for o in &r.outliers {
                let at = o.line.map_or(format!("measurement {}", o.measurement), |l| format!("line {l}"));
                writeln!(f, "  {at:<16} residual {:.4} mm", o.residual_mm)?;
            }
            Ok(())
        }
    }?;
    for c in &s.clusters {
        let [lo, hi] = c.residual_mm;
        writeln!(
            f,
            "  not gross errors: {} poses {} depart together by {lo:.2}–{hi:.2} mm — kept, a systematic effect (see the warnings)",
            c.kept,
            c.place()
        )?;
    }
    Ok(())
}

/// One row of held-out statistics.
fn line(f: &mut fmt::Formatter<'_>, what: &str, s: &Stats) -> fmt::Result {
    writeln!(
        f,
        "  {what:<44} {:>9.4} {:>9.4} {:>9.4} {:>9.4} {:>9.4}",
        s.heldout_mean_mm, s.heldout_median_mm, s.heldout_p95_mm, s.heldout_rms_mm, s.heldout_max_mm
    )
}

/// The header of the held-out statistics' columns.
fn header(f: &mut fmt::Formatter<'_>) -> fmt::Result {
    writeln!(f, "  {:<44} {:>9} {:>9} {:>9} {:>9} {:>9}", "model", "mean", "median", "p95", "RMS", "max")
}

/// The held-out errors: nested, the hold-out set, the selection's own tables.
fn heldout(r: &Report, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    if let Some(n) = &r.nested {
        writeln!(
            f,
            "held-out error of the whole diagnosis, nested {}-fold (each outer test fold unseen by the selection), mm:",
            n.outer_folds
        )?;
        header(f)?;
        line(f, "nominal", &n.nominal)?;
        line(f, "the effects each outer selection chose", &n.selected)?;
        // Shown where an outer fold's completion was turned down: the model a small set falls back to.
        if n.complete != n.selected {
            line(f, "the completed geometry each fold judged", &n.complete)?;
        }
        for fold in &n.folds {
            let chosen = if fold.effects.is_empty() { "none".to_string() } else { fold.effects.join(", ") };
            let flag =
                if fold.selected.heldout_rms_mm > fold.nominal.heldout_rms_mm { "  WORSE THAN NOMINAL" } else { "" };
            writeln!(
                f,
                "    outer fold {} ({} poses): nominal {:.4} → {:.4} mm RMS{flag}; chose {chosen}",
                fold.fold, fold.poses, fold.nominal.heldout_rms_mm, fold.selected.heldout_rms_mm
            )?;
        }
        if let Some(d) = n.dominated_by {
            writeln!(
                f,
                "    outer fold {d} holds more than half of the squared error: the RMS above is mostly that fold"
            )?;
        }
    }
    if let Some(h) = &r.holdout {
        writeln!(f, "\nexplicit hold-out set (fitted on all measurements; never used to choose), mm:")?;
        if !h.refitted.is_empty() {
            writeln!(
                f,
                "  in the training frame (the model as fitted and exported, nothing refitted: the use-test when both files share the tracker frame and probe):"
            )?;
            header(f)?;
            line(f, "nominal", &h.same_frame.nominal)?;
            line(f, "the effects chosen below", &h.same_frame.selected)?;
            writeln!(
                f,
                "  in its own frame and with its own probe ({} refitted on it, the effects kept):",
                h.refitted.join(", ")
            )?;
        }
        header(f)?;
        line(f, "nominal", &h.nominal)?;
        line(f, "the effects chosen below", &h.selected)?;
    }
    if let Some(a) = &r.at_use {
        at_use(f, a)?;
    }
    writeln!(f, "\nselection: {} — scores that chose the effects (optimistic):", r.validation)?;
    writeln!(f, "  {:<44} {:>9} {:>9} {:>9}", "model", "mean", "RMS", "max")?;
    for row in &r.additive {
        writeln!(
            f,
            "  {:<44} {:>9.4} {:>9.4} {:>9.4}",
            row.model, row.stats.heldout_mean_mm, row.stats.heldout_rms_mm, row.stats.heldout_max_mm
        )?;
    }
    if !r.leave_one_out.is_empty() {
        if r.completed.is_empty() {
            writeln!(f, "\nleave one out (mm):")?;
        } else {
            writeln!(
                f,
                "\nleave one out (mm; an effect from the diagnosed effects, a completion row from the completed model):"
            )?;
        }
        for row in &r.leave_one_out {
            writeln!(
                f,
                "  {:<44} {:>9.4} {:>9.4} {:>9.4}",
                row.model, row.stats.heldout_mean_mm, row.stats.heldout_rms_mm, row.stats.heldout_max_mm
            )?;
        }
    }
    Ok(())
}

/// The effects, main cause first, with their parameters; then the rows and compliances the completion added.
fn effects(r: &Report, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    writeln!(f, "\neffects, main cause first (the one whose removal raises the held-out error most):")?;
    if r.effects.is_empty() {
        writeln!(
            f,
            "  none: no candidate lowers the held-out mean squared error by more than one standard error of the paired difference"
        )?;
    }
    if !r.effects.is_empty() && !r.completed.is_empty() {
        let shrunk = if r.shrinkage > 0.0 { ", shrunk toward the nominal robot" } else { "" };
        writeln!(
            f,
            "  (their values as fitted without the completion's rows, which share them out; the export carries the completed fit{shrunk})"
        )?;
    }
    for e in &r.effects {
        effect(e, f)?;
    }
    if !r.completed.is_empty() {
        writeln!(
            f,
            "\ncompleted for use (not causes found: the joint rows and compliances a robot used in its training frame needs beside them; in every score above and in the export):"
        )?;
        for e in &r.completed {
            effect(e, f)?;
        }
    }
    Ok(())
}

/// One effect: its steps, leave-one-out error, relations and parameters.
fn effect(e: &crate::report::EffectReport, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let steps = match (e.heldout_rms_before_mm, e.heldout_rms_after_mm) {
        (Some(b), Some(a)) => format!("held-out RMS {b:.4} → {a:.4} mm"),
        (None, Some(a)) => format!("held-out RMS → {a:.4} mm (joined: {})", e.joined),
        _ => "held-out RMS: not in the additive table".to_string(),
    };
    let list =
        |what: &str, v: &[String]| if v.is_empty() { String::new() } else { format!("; {what}: {}", v.join(", ")) };
    writeln!(
        f,
        "  {:<30} {steps} (without it: {:.4}){}{}{}",
        e.label,
        e.heldout_rms_without_mm,
        list("equivalent", &e.equivalent),
        list("contained in", &e.contained_in),
        list("contains", &e.contains)
    )?;
    for (name, v) in &e.parameters {
        match (&v.fixed, v.std) {
            (Some(why), _) => writeln!(f, "      {name:<44} {:>12.6}   fixed, not fitted: {why}", v.value)?,
            (None, Some(sd)) => writeln!(f, "      {name:<44} {:>12.6} ± {sd:.6}", v.value)?,
            (None, None) => {
                writeln!(f, "      {name:<44} {:>12.6}   (no uncertainty: singular normal matrix)", v.value)?
            }
        }
    }
    Ok(())
}

/// The fitted frames, nearly unidentifiable pairs, the verdict and where the residuals lie.
fn frames_and_verdict(r: &Report, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    if let Some(reg) = &r.frames.registration {
        let [x, y, z] = reg.position_mm;
        let [a, b, c] = reg.xyz_euler_deg;
        writeln!(
            f,
            "\nfitted registration (measurement frame ← base): {x:.4}, {y:.4}, {z:.4} mm; {a:.5}, {b:.5}, {c:.5}° (X-Y-Z Euler)"
        )?;
    }
    if let Some([x, y, z]) = r.frames.tool_point_mm {
        write!(f, "fitted tool point, in the robot's tip frame (its last link): {x:.4}, {y:.4}, {z:.4} mm")?;
        if let Some([a, b, c]) = r.frames.tool_point_joint_frame_mm {
            write!(f, " (in the last joint's same-orientation frame: {a:.4}, {b:.4}, {c:.4} mm)")?;
        }
        writeln!(f)?;
    }
    if let Some([x, y, z]) = r.frames.tool_rotation_deg {
        writeln!(f, "fitted probe rotation (tool row's X-Y-Z error angles): {x:.5}, {y:.5}, {z:.5}°")?;
    }
    if !r.identifiability.correlated.is_empty() {
        writeln!(
            f,
            "\nnearly unidentifiable combinations (estimates correlated above 0.99: their combination is determined, not each):"
        )?;
        for c in &r.identifiability.correlated {
            writeln!(f, "  {} ~ {} (correlation {:+.4})", c.a, c.b, c.correlation)?;
        }
    }
    writeln!(f, "\nverdict: {}", r.verdict)?;
    writeln!(f, "\nwhere the nominal model's residuals lie (RMS, mm; → after the effects found):")?;
    let (b, a) = (&r.residuals_before, &r.residuals_after);
    for (j, (qb, qa)) in b.by_joint.iter().zip(&a.by_joint).enumerate() {
        writeln!(
            f,
            "  joint {} angle quartiles   {}   →   {}",
            j + 1,
            qb.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(" "),
            qa.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(" ")
        )?;
    }
    let four = |v: &[Option<f64>; 4]| {
        v.iter().map(|x| x.map_or_else(|| "no-poses".to_string(), |x| format!("{x:.4}"))).collect::<Vec<_>>().join(" ")
    };
    writeln!(
        f,
        "  workspace (near-low near-high far-low far-high)   {}   →   {}",
        four(&b.by_workspace_region),
        four(&a.by_workspace_region)
    )?;
    writeln!(
        f,
        "  joint space (elbow × wrist)                       {}   →   {}",
        four(&b.by_joint_space_region),
        four(&a.by_joint_space_region)
    )?;
    if !b.by_time.is_empty() {
        let list = |v: &[f64]| v.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(" ");
        writeln!(
            f,
            "  time quartiles                                    {}   →   {}",
            list(&b.by_time),
            list(&a.by_time)
        )?;
    }
    Ok(())
}

/// What the data cannot identify, observability, fixed parameters.
fn identifiability(r: &Report, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    if !r.identifiability.not_identifiable.is_empty() {
        writeln!(
            f,
            "\nrefused: not identifiable from these data, or fitted beyond physical sense (each with what to do):"
        )?;
        for x in &r.identifiability.not_identifiable {
            writeln!(f, "  {:<30} {} — {}", x.effect, x.reason, x.remedy)?;
        }
    }
    if !r.identifiability.skipped_candidates.is_empty() {
        writeln!(f, "\nadding nothing identifiable beside the model they were scored with (another block's freedom):")?;
        for x in &r.identifiability.skipped_candidates {
            writeln!(f, "  {:<30} {}", x.effect, x.reason)?;
        }
    }
    if let Some(o) = &r.identifiability.observability {
        writeln!(
            f,
            "\nidentifiability: {} parameters from {} residuals; condition number {:.3e}; O1 {:.3e} O2 {:.3e} O3 {:.3e} O4 {:.3e} O5 {:.3e}",
            o.parameters, o.rows, o.condition_number, o.o1, o.o2, o.o3, o.o4, o.o5
        )?;
    }
    for fixed in &r.identifiability.fixed {
        writeln!(f, "  fixed {}: {}", fixed.parameter, fixed.reason)?;
    }
    Ok(())
}

/// The prediction at the poses of use ([`crate::AtUse`]) and, where a hold-out set holds those poses, how
/// its measured RMS compares.
fn at_use(f: &mut std::fmt::Formatter<'_>, a: &crate::report::AtUse) -> std::fmt::Result {
    let frame = if a.refitted > 0 {
        format!(", the {} frame parameters a test fits there refitted", a.refitted)
    } else {
        String::new()
    };
    writeln!(
        f,
        "\npredicted at the {} poses of use (the final model's least-squares fit, its residuals' scale {:.4} mm per coordinate{frame}): held-out RMS {:.4} mm, of which the model's parameters {:.4} mm; a test there resolves {:.1} % of it",
        a.poses,
        a.residual_scale_mm,
        a.predicted_rms_mm,
        a.model_rms_mm,
        100.0 * a.resolution
    )?;
    if let Some(p) = a.promised_rms_mm {
        let against = a.measured_rms_mm.map_or(String::new(), |m| format!(": measured {:.2} × of it", m / p));
        let stand_ins = match a.promised_at_nearest {
            0 => String::new(),
            n => format!(", {n} of the poses taken at their nearest candidate as the plan was made"),
        };
        writeln!(
            f,
            "  the plan promised {p:.4} mm there at this residual scale (its figure at the tracker's noise, scaled by the scale found{stand_ins}){against}"
        )?;
    }
    if let Some(m) = a.measured_rms_mm {
        let ratio = m / a.predicted_rms_mm;
        let reading = if (ratio - 1.0).abs() <= 2.0 * a.resolution {
            "as predicted, within a test's resolution".to_string()
        } else if ratio > 1.0 {
            format!(
                "{ratio:.2} × the prediction: the model errs more there than where it was fitted (it is not the robot there, or the poses of use leave the measured arcs)"
            )
        } else {
            format!("{ratio:.2} × the prediction: better than its own residuals promised")
        };
        writeln!(
            f,
            "  the hold-out set holds these poses: measured {m:.4} mm RMS (registration and tool refitted on it) — {reading}"
        )?;
    }
    Ok(())
}
