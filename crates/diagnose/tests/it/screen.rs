//! The screened selection (candidates ranked by a linearised step, a shortlist fitted in full) against the
//! exhaustive one (every candidate fitted in full, `Screen { keep: 0 }`): the same effects chosen in the
//! same order with the same held-out figures, on simulated sets of every kind and on the real ones.

use thermokin_chain::{Chain, ErrorParams};
use thermokin_chain::{Dataset, Robot};
use thermokin_diagnose::{Config, Fitted, Report, Screen, Validation, diagnose};
use thermokin_identify::{FrameMode, ToolMode};
use thermokin_testdata::{error_mm_deg, workspace};

use crate::tracker::measure;

fn irb140() -> Robot {
    thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap()
}

/// The chosen effects and every row of the additive table, as the report gives them.
fn choices(r: &Report) -> Vec<(String, f64, f64)> {
    r.additive.iter().map(|row| (row.model.clone(), row.stats.heldout_rms_mm, row.stats.heldout_mean_mm)).collect()
}

fn compare(name: &str, robot: &Robot, data: &Dataset, config: Config) {
    let screened =
        diagnose(robot, data, None, &Config { validation: Validation::SelectionOnly, ..config.clone() }).unwrap();
    let exhaustive = diagnose(
        robot,
        data,
        None,
        &Config { validation: Validation::SelectionOnly, screen: Screen { keep: 0, fitted: Fitted::Every }, ..config },
    )
    .unwrap();
    let (a, b) = (choices(&screened), choices(&exhaustive));
    eprintln!("{name}: screened {:?}", a.iter().map(|r| &r.0).collect::<Vec<_>>());
    assert_eq!(a.len(), b.len(), "{name}: screened {a:?}\nexhaustive {b:?}");
    for (x, y) in a.iter().zip(&b) {
        // The same models fitted the same way: equal figures, RMS and mean (a different fit order in
        // parallel reductions may move the last bits).
        let same = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.max(1.0);
        assert!(x.0 == y.0 && same(x.1, y.1) && same(x.2, y.2), "{name}: {x:?} vs {y:?}");
    }
}

fn with(chain: &Chain, rows: &[(usize, [f64; 6])], zeros: &[(usize, f64)]) -> Chain {
    let mut errors = vec![ErrorParams::ZERO; 6];
    for &(j, e) in rows {
        errors[j] = error_mm_deg(e);
    }
    let mut z = vec![0.0; 6];
    for &(j, deg) in zeros {
        z[j] = deg.to_radians();
    }
    chain
        .with_errors_and_zeros(error_mm_deg([0.5, -0.3, 0.4, 0.02, -0.01, 0.015]), &errors, ErrorParams::ZERO, &z)
        .unwrap()
}

#[test]
fn screened_and_exhaustive_selections_agree_on_simulated_sets() {
    let robot = irb140();
    let truth = with(robot.chain(), &[(2, [0.3, -0.2, 0.25, 0.02, 0.0, 0.015])], &[(1, 0.05)]);
    compare("geometry", &robot, &measure(&truth, 150, 21, <[f64]>::to_vec), Config::default());
    let scaled = measure(robot.chain(), 200, 31, |q| {
        let mut a = q.to_vec();
        a[1] *= 1.0 + 5e-4;
        a[2] += 0.03f64.to_radians() * (q[2] + 40f64.to_radians()).sin();
        a
    });
    compare("gear ratio and cyclic", &robot, &scaled, Config::default());
}

#[test]
fn screened_and_exhaustive_selections_agree_on_real_sets() {
    let (robot, data) = crate::real_data::rokae();
    let config = Config { frame: FrameMode::Tracker, tool: ToolMode::Unknown, ..Config::default() };
    compare("Rokae robot B", &robot, &data, config.clone());
    let options = thermokin_io::RobotOptions { base: None, tip: Some("tool0".into()) };
    let ur10 = thermokin_io::read_robot_with(&thermokin_testdata::urdf("ur10.urdf"), &options).unwrap();
    let kinds: Vec<_> = ur10.chain().joints().iter().map(|j| j.kind).collect();
    let c = thermokin_io::read_measurements(&workspace("fixtures/real/ur10-ipa/series_C.csv"), &kinds).unwrap();
    let every: Vec<usize> = (0..c.len()).step_by(6).collect();
    compare("UR10 series C, every 6th pose", &ur10, &c.subset(&every), config);
}
