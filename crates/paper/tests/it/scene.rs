use thermokin_deform::{CoppeliaSimEdits, TableSemantics};
use thermokin_io::{PaperResultRow, read_deviation_table, read_paper_results, read_robot};
use thermokin_paper::{
    Verdict, identify_scene_geometry, identify_tool_point, residuals, scene_chain, single_precision_evidence,
    static_hypotheses, transient_candidates,
};
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
    // The geometry beyond Table 9, identified on the same rows: the joint rows' translations, rank 12 of
    // 18, micrometres; rotations stay Table 9's. The config prints nine decimals (mm): ≤ 5e-10 per number.
    let (geometry, rank) = identify_scene_geometry(&identified, &minute0(&rows)).unwrap();
    assert_eq!(rank, 12);
    for (i, (a, b)) in geometry.joints().iter().zip(shipped.joints()).enumerate() {
        let (ea, eb) = (a.error, b.error);
        eprintln!("joint {}: identified {:?} shipped {:?}", i + 1, ea, eb);
        assert!((ea.translation - eb.translation).amax() < 1e-9, "joint {}", i + 1);
        assert!((ea.rotation - eb.rotation).amax() < 1e-9f64.to_radians(), "joint {}", i + 1);
        assert!(ea.translation.amax() < 0.01 && ea.rotation == eb.rotation, "joint {}: {ea:?}", i + 1);
        assert_eq!(b.error.rotation, nalgebra::Vector3::zeros());
    }
    // The joint points and axes are Table 9's.
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
    let d =
        table9_tool.tool_pose(&q).unwrap().translation.vector - identified.tool_pose(&q).unwrap().translation.vector;
    assert!(d.norm() < 1e-9, "{d:?}");
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
    // The goal: 0.005 mm in every one of the 50 rows (against 0.4517 mm RMS on Table 9). Measured:
    // 0.00085 mm RMS, worst 0.0011 mm — the files print 0.001 mm, and the geometry was identified on other
    // rows (the transient file's minute 0), never on these.
    assert!(r.worst_mm <= 0.005, "worst {} mm ({})", r.worst_mm, r.worst_row);
    // Drift pin (±0.2 µm), so that a change of the scene or of the deformation code shows; not a goal.
    assert!((r.rms_mm - 0.00085).abs() < 0.0002 && (r.worst_mm - 0.0011).abs() < 0.0002, "{r:?}");
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
    // Finding, not a goal met: no candidate reaches the file (see docs/paper-reproduction.md). The
    // per-minute increment at home, read back as CoppeliaSim reads Euler angles (joint 4's object sits
    // at the gimbal lock at home), comes closest: 5.05 → 1.21 mm RMS over the 10,050 rows.
    let scene = read_robot(&workspace("configs/irb140-scene.toml")).unwrap().chain().clone();
    let table = read_deviation_table(&authors("deformations-case-study.csv")).unwrap();
    let candidates = transient_candidates(&scene, &table, &transient()).unwrap();
    assert_eq!(candidates.len(), 3);
    for c in &candidates {
        eprintln!(
            "{}: minute 1 {:.4} mm, minute 180 {:.4} mm, all rows RMS {:.4} mm",
            c.name, c.minute1.rms_mm, c.minute180.rms_mm, c.all.rms_mm
        );
        assert!(c.all.rows == 10_050);
        assert!(c.minute1.rms_mm > 0.02, "{} now fits minute 1: {}", c.name, c.minute1.rms_mm);
    }
    let best = candidates.iter().min_by(|a, b| a.all.rms_mm.total_cmp(&b.all.rms_mm)).unwrap();
    assert!(best.name.contains("robot at home"), "{}", best.name);
    // Drift pins (±1 µm at minute 1, ±1 mm‰ of the RMS), so that a change of the deformation code shows.
    assert!((best.minute1.rms_mm - 0.0543).abs() < 0.001, "{:?}", best.minute1);
    assert!((best.all.rms_mm - 1.2133).abs() < 0.002, "{:?}", best.all);
    assert!((candidates[0].all.rms_mm - 5.0509).abs() < 0.002, "{:?}", candidates[0].all);
}

#[test]
fn the_authors_angles_are_single_precision_numbers() {
    let rows = transient();
    let evidence = single_precision_evidence(&rows);
    eprintln!("{evidence:?}");
    assert!(evidence.angles > 3000, "{evidence:?}");
    assert!(evidence.worst_fraction_of_spacing < 0.15, "{evidence:?}");
    // Controls for the rule itself, built without the authors' data: angles printed to 1e-6° the way
    // their files print them (truncated), from double-precision values and from 32-bit floats.
    let printed = |deg: f64| (deg * 1e6).trunc() / 1e6;
    let row_of = |q: f64| {
        let mut r = rows[0].clone();
        r.joints = vec![q; 6];
        r
    };
    let (mut doubles, mut floats) = (Vec::new(), Vec::new());
    for k in 0..2000 {
        // A deterministic spread over [1, 2) rad.
        let q = 1.0 + (k as f64 * 0.618_033_988_749_895).fract();
        doubles.push(row_of(printed(q.to_degrees()).to_radians()));
        floats.push(row_of(printed(f64::from(q as f32).to_degrees()).to_radians()));
    }
    let d = single_precision_evidence(&doubles);
    let f = single_precision_evidence(&floats);
    assert!(d.worst_fraction_of_spacing > 0.45, "{d:?}");
    assert!(f.worst_fraction_of_spacing < 0.15, "{f:?}");
}
