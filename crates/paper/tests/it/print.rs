//! The printed Tables 13, 15, 17 and 18 against the authors' own files (print vs file), and Table 15
//! against their angles evaluated on the replayed scene (print vs model). Tolerances are the printed
//! precision: one unit of each figure's last printed digit (the print truncates).

use thermokin_deform::{CoppeliaSimEdits, TableSemantics};
use thermokin_io::{read_deviation_table, read_paper_results, read_robot};
use thermokin_paper::print::{
    TABLE_13, TABLE_15, TABLE_17, TABLE_18, compare, file_orientation_deviation, file_position_deviation,
    printed_value, replayed_position_deviation,
};
use thermokin_paper::residuals;
use thermokin_testdata::{authors, workspace};

#[test]
fn the_static_tables_are_the_authors_file() {
    let rows = read_paper_results(&authors("results-static-case-study.csv")).unwrap();
    let (lo, hi) = file_position_deviation(&rows);
    for f in compare(&TABLE_15, lo, hi) {
        assert!(f.agrees(), "Table 15 {} axis {}: printed {}, file {}", f.bound, f.axis, f.printed, f.computed);
    }
    let (lo, hi) = file_orientation_deviation(&rows);
    for f in compare(&TABLE_13, lo, hi) {
        assert!(f.agrees(), "Table 13 {} axis {}: printed {}, file {}", f.bound, f.axis, f.printed, f.computed);
    }
}

#[test]
fn the_transient_tables_are_the_authors_file_but_for_one_slip() {
    let rows = read_paper_results(&authors("results-transient-case-study.csv")).unwrap();
    let (lo, hi) = file_position_deviation(&rows);
    for f in compare(&TABLE_17, lo, hi) {
        assert!(f.agrees(), "Table 17 {} axis {}: printed {}, file {}", f.bound, f.axis, f.printed, f.computed);
    }
    let (lo, hi) = file_orientation_deviation(&rows);
    let figures = compare(&TABLE_18, lo, hi);
    let slips: Vec<_> = figures.iter().filter(|f| !f.agrees()).collect();
    // Finding: Table 18 prints ΔθZ 10× smaller than the file (−0.007 / 0.004 for −0.07 / 0.04). Every
    // other figure agrees; the two that do not are exactly that slip.
    assert_eq!(slips.len(), 2, "{slips:?}");
    for f in slips {
        assert_eq!(f.axis, 2);
        let printed = printed_value(f.printed).0;
        assert!((f.computed - 10.0 * printed).abs() < 10.0 * f.unit, "{f:?}");
    }
}

#[test]
fn their_static_angles_on_the_replayed_scene_give_table_15() {
    // Table 15 is the authors' solver's residual: programmed − where their angles put the TCP. Recomputed
    // here from their angles on our replay of their scene, it agrees with print to the printed precision
    // plus the replay's own accuracy on the same rows (its worst residual, computed, not assumed).
    let scene = read_robot(&workspace("configs/irb140-scene.toml")).unwrap().chain().clone();
    let table = read_deviation_table(&authors("deformations-case-study.csv")).unwrap();
    let replayed = table.apply(&scene, &TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; 6]))).unwrap();
    let rows = read_paper_results(&authors("results-static-case-study.csv")).unwrap();
    let accuracy = residuals(&replayed, &rows).unwrap().worst_mm;
    let (lo, hi) = replayed_position_deviation(&replayed, &rows).unwrap();
    let mut worst: f64 = 0.0;
    for f in compare(&TABLE_15, lo, hi) {
        let gap = (f.computed - printed_value(f.printed).0).abs();
        worst = worst.max(gap);
        assert!(
            gap < f.unit + accuracy,
            "Table 15 {} axis {}: printed {}, replayed {}",
            f.bound,
            f.axis,
            f.printed,
            f.computed
        );
    }
    eprintln!(
        "Table 15 from their angles on the replay: worst gap to print {worst:.4} mm (replay accuracy {accuracy:.4} mm)"
    );
    // On Table 9 as printed (no scene), the same recomputation misses print by the 0.45 mm of the issue.
    let table9 = read_robot(&workspace("configs/irb140.toml")).unwrap().chain().clone();
    let on_table9 = table.apply(&table9, &TableSemantics::CoppeliaSim(CoppeliaSimEdits::at(vec![0.0; 6]))).unwrap();
    let (lo, hi) = replayed_position_deviation(&on_table9, &rows).unwrap();
    let worst9 =
        compare(&TABLE_15, lo, hi).iter().map(|f| (f.computed - printed_value(f.printed).0).abs()).fold(0.0, f64::max);
    assert!(worst9 > 0.3, "{worst9}");
}
