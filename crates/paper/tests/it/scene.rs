use thermokin_deform::{CoppeliaSimEdits, TableSemantics};
use thermokin_io::{PaperResultRow, read_deviation_table, read_paper_results, read_robot};
use thermokin_paper::{Verdict, identify_tool_point, residuals, scene_chain, static_hypotheses, transient_candidates};
use thermokin_testdata::{authors, workspace};

fn transient() -> Vec<PaperResultRow> {
    read_paper_results(&authors("results-transient-case-study.csv")).unwrap()
}

fn minute0(rows: &[PaperResultRow]) -> Vec<&PaperResultRow> {
    let m0: Vec<&PaperResultRow> = rows.iter().filter(|r| r.time_min == 0.0).collect();
    assert_eq!(m0.len(), 50);
    m0
}

#[test]
fn the_shipped_scene_is_what_minute_zero_identifies() {
    let table9 = read_robot(&workspace("configs/irb140.toml")).unwrap().chain().clone();
    let shipped = read_robot(&workspace("configs/irb140-scene.toml")).unwrap().chain().clone();
    let rows = transient();
    let tool_point = identify_tool_point(&table9, &minute0(&rows)).unwrap();
    eprintln!("identified tool point (joint 6 frame): {:?} mm", tool_point.as_slice());
    // 14 µm shorter than Table 9's 25.5 mm, and a few µm off the axis.
    assert!((tool_point.x - 25.5).abs() < 0.02 && tool_point.yz().norm() < 0.01, "{tool_point:?}");
    let identified = scene_chain(&table9, tool_point).unwrap();
    // The config prints six decimals: rounding ≤ 5e-7 mm per number.
    let a6 = |c: &thermokin_chain::Chain| c.joints()[5].offset;
    assert!((a6(&identified) - a6(&shipped)).norm() < 1e-6, "{:?} vs {:?}", a6(&identified), a6(&shipped));
    assert!((identified.tool().translation - shipped.tool().translation).norm() < 1e-6);
    // Everything else is Table 9.
    for (a, b) in table9.joints().iter().zip(shipped.joints()).take(5) {
        assert_eq!(a.offset, b.offset);
        assert_eq!(a.axis, b.axis);
    }
    // Nominal FK of the scene equals Table 9 with the identified tool: moving joint 6's point along its
    // axis changes nothing until the script's edits pivot about it.
    let q = [0.3, -0.2, 0.5, 1.0, -0.7, 2.0];
    let mut tool = table9.tool().clone();
    tool.translation = tool_point;
    let table9_tool = table9.with_tool(tool).unwrap();
    let d = table9_tool.tool_pose(&q).unwrap().translation.vector - shipped.tool_pose(&q).unwrap().translation.vector;
    assert!(d.norm() < 1e-5, "{d:?}");
}

#[test]
fn static_replay_on_the_scene_reproduces_the_authors_coordinates() {
    // The scene's robot, the authors' own deformation file, their script's semantics, their 50 angles.
    let scene = read_robot(&workspace("configs/irb140-scene.toml")).unwrap().chain().clone();
    let table = read_deviation_table(&authors("deformations-case-study.csv")).unwrap();
    let deformed = table.apply(&scene, &TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; 6]))).unwrap();
    let static_rows = read_paper_results(&authors("results-static-case-study.csv")).unwrap();
    assert_eq!(static_rows.len(), 50);
    let r = residuals(&deformed, &static_rows).unwrap();
    eprintln!("static replay: {r:?}");
    // The goal, 0.005 mm, holds as an RMS over the 50 rows (measured 0.0034 mm, against 0.4517 mm
    // on Table 9).
    assert!(r.rms_mm <= 0.005, "RMS {} mm", r.rms_mm);
    // It does NOT hold row by row: the worst row is 0.0060 mm, 1 µm over. The same 0.0057 mm worst is left
    // on minute 0 by the nominal scene itself, where no deformation is involved: the scene's geometry
    // beyond Table 9 and its tool point. Pinned (±0.2 µm) so that a change shows; not a tolerance.
    assert!((r.worst_mm - 0.0060).abs() < 0.0002, "worst {} mm ({})", r.worst_mm, r.worst_row);
    // Orientation: within twice the floor of the nominal minute-0 rows (the verdict rule of
    // `static_hypotheses`); the published Euler angles are rounded.
    let floor = residuals(&scene, minute0(&transient())).unwrap();
    assert!(
        r.worst_orientation_deg <= 2.0 * floor.worst_orientation_deg,
        "{} vs {}",
        r.worst_orientation_deg,
        floor.worst_orientation_deg
    );
}

#[test]
fn only_joint_six_at_the_flange_explains_the_static_gap() {
    let table9 = read_robot(&workspace("configs/irb140.toml")).unwrap().chain().clone();
    let table = read_deviation_table(&authors("deformations-case-study.csv")).unwrap();
    let static_rows = read_paper_results(&authors("results-static-case-study.csv")).unwrap();
    let rows = transient();
    let (floor, hypotheses) = static_hypotheses(&table9, &table, &minute0(&rows), &static_rows).unwrap();
    eprintln!("floor (nominal scene, minute 0): {floor:?}");
    for h in &hypotheses {
        eprintln!(
            "{:?} {:.4} mm RMS, {:.4}° — {}",
            h.verdict, h.residuals.rms_mm, h.residuals.worst_orientation_deg, h.name
        );
    }
    let kept: Vec<&str> = hypotheses.iter().filter(|h| h.verdict == Verdict::Kept).map(|h| h.name.as_str()).collect();
    assert_eq!(kept.len(), 1, "{kept:?}");
    assert!(kept[0].starts_with("joint 6's object at the flange"), "{kept:?}");
    // As published: the 0.45 mm of the issue.
    assert!((hypotheses[0].residuals.rms_mm - 0.4517).abs() < 0.0005);
    // Dropping row 6's rotation fits the positions just as well but turns the tool 2.2° away from the
    // published orientations: rejected by the orientation columns.
    let dropped = hypotheses.iter().find(|h| h.name.starts_with("row 6's rotation")).unwrap();
    assert!(dropped.residuals.rms_mm < 0.005 && dropped.residuals.worst_orientation_deg > 2.0);
}

#[test]
fn the_transient_replays_tried_so_far_do_not_reproduce_the_file() {
    // Finding, not a goal met: neither candidate reaches the file (see docs/paper-reproduction.md). Pinned
    // to 1 µm at minute 1 so that a change of the deformation code shows here.
    let scene = read_robot(&workspace("configs/irb140-scene.toml")).unwrap().chain().clone();
    let table = read_deviation_table(&authors("deformations-case-study.csv")).unwrap();
    let candidates = transient_candidates(&scene, &table, &transient()).unwrap();
    for c in &candidates {
        eprintln!(
            "{}: minute 1 {:.4} mm, minute 180 {:.4} mm, all rows RMS {:.4} mm",
            c.name, c.minute1.rms_mm, c.minute180.rms_mm, c.all.rms_mm
        );
        assert!(c.all.rows == 10_050);
        assert!(c.minute1.rms_mm > 0.02, "{} now fits minute 1: {}", c.name, c.minute1.rms_mm);
    }
}
