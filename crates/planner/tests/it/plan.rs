//! The plan's own properties: a subset of the candidates, a shorter path, a criterion that only improves,
//! and predicted standard deviations that the spread of real fits confirms.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use thermokin_chain::{Dataset, Measurement, Robot};
use thermokin_identify::{Effect, JointIndex, Model, PoseTerms, fit};
use thermokin_planner::{Candidates, Criterion, Params, Poses, plan};

fn irb140() -> Robot {
    thermokin_io::read_robot(&thermokin_testdata::workspace("configs/irb140.toml")).unwrap()
}

#[test]
fn the_plan_is_a_subset_of_the_candidates_in_a_shorter_order() {
    let robot = irb140();
    let pool = Candidates::sampled(&robot, 400, 11, None).unwrap();
    // The D-optimal machinery (the criterion a log det); the prediction criterion's in the test below.
    let params = Params { poses: Poses::Exactly(25), criterion: Criterion::Parameters, ..Params::default() };
    let p = plan(&robot, &pool, &[], &params).unwrap();
    assert_eq!(p.poses.len(), 25);
    let mut seen = std::collections::HashSet::new();
    for pose in &p.poses {
        // The candidate's values, bit for bit, and each candidate at most once.
        assert_eq!(pose.joints_rad, pool.joints()[pose.candidate]);
        assert!(seen.insert(pose.candidate));
    }
    assert!(p.motion.ordered <= p.motion.as_chosen, "{:?}", p.motion);
    // The criterion after each pose in measuring order never decreases, and its last value is the plan's
    // criterion computed afresh (a Cholesky factorisation of the whole plan's information).
    assert!(p.criterion_by_pose.windows(2).all(|w| w[1] >= w[0]), "{:?}", p.criterion_by_pose);
    let last = *p.criterion_by_pose.last().unwrap();
    assert!((last - p.comparison.planned_criterion).abs() < 1e-6 * last.abs().max(1.0));
    // Planned beats random of the same pool on the criterion it optimises, and on the condition number.
    assert!(p.comparison.planned_criterion > p.comparison.random_criterion);
    let (planned, random) = (p.comparison.planned.as_ref().unwrap(), p.comparison.random.as_ref().unwrap());
    assert!(planned.condition_number < random.condition_number, "{planned:?} {random:?}");
}

#[test]
fn bad_settings_and_candidates_are_refused_with_their_reason() {
    let robot = irb140();
    let pool = Candidates::sampled(&robot, 10, 1, None).unwrap();
    let e = plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(11), ..Params::default() }).unwrap_err();
    assert_eq!(e.to_string(), "11 poses asked for, but only 10 candidates");
    let e = plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(0), ..Params::default() }).unwrap_err();
    assert!(e.to_string().contains("at least one pose"), "{e}");
    let e = Candidates::new(&robot, vec![vec![0.0; 6], vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0]], vec![2, 3]).unwrap_err();
    assert_eq!(e.to_string(), "candidate 3: joint 3 is outside its limits");
    let e = Candidates::new(&robot, vec![vec![0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0]], vec![]).unwrap_err();
    assert_eq!(e.to_string(), "candidate 1: joint 2 is not a finite number");
    let drift = Effect::ThermalDrift(JointIndex::of(&robot, 1).unwrap(), thermokin_identify::DriftShape::Linear);
    let e =
        plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(5), effects: Some(vec![drift]), ..Params::default() })
            .unwrap_err();
    assert!(e.to_string().starts_with("thermal_drift[2] (linear) is identified over operating time"), "{e}");
}

/// The predicted σ of every parameter, at the stated noise, against the spread of 300 fits of the same
/// model to the planned poses measured with that noise. The measurements are the chain's FK plus seeded
/// Gaussian noise — not the planner's model —, and each fit is the identification's Levenberg–Marquardt.
/// 300 fits estimate a standard deviation to ±4 % (1/√(2·300)): 20 % is five of those.
#[test]
fn the_predicted_sigma_matches_the_spread_of_fits_over_simulated_noise() {
    let robot = irb140();
    let j = |k: usize| JointIndex::of(&robot, k).unwrap();
    let mut effects: Vec<Effect> = (0..6).map(|k| Effect::JointOffset(j(k))).collect();
    effects.push(Effect::LinkDeviation(j(2)));
    let pool = Candidates::sampled(&robot, 500, 5, None).unwrap();
    let params =
        Params { poses: Poses::Exactly(20), noise_mm: 0.05, effects: Some(effects.clone()), ..Params::default() };
    let p = plan(&robot, &pool, &[], &params).unwrap();
    let model = Model::new(&robot, effects).unwrap();
    let names = model.parameter_names();
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let fits: Vec<Vec<f64>> = (0..300)
        .map(|_| {
            let measurements = p
                .poses
                .iter()
                .map(|pose| {
                    let truth = robot.chain().tool_pose(&pose.joints_rad).unwrap().translation.vector;
                    let noise =
                        nalgebra::Vector3::from_fn(|_, _| params.noise_mm * thermokin_testdata::gauss(&mut rng));
                    Measurement {
                        time_min: 0.0,
                        q: pose.joints_rad.clone(),
                        position_mm: truth + noise,
                        orientation: None,
                        position_std_mm: None,
                        temps: vec![],
                    }
                })
                .collect();
            let data = Dataset { measurements, ..Dataset::default() };
            let rows: Vec<usize> = (0..data.len()).collect();
            fit(&robot, &model, &data, &rows, &PoseTerms::of(&robot, &data, 0.0)).unwrap().theta
        })
        .collect();
    let mut checked = 0;
    for (c, name) in names.iter().enumerate() {
        let Some(predicted) = p.parameters.iter().find(|x| &x.parameter == name).and_then(|x| x.planned) else {
            continue;
        };
        let (effect, k) = model.parameter(c).unwrap();
        let values: Vec<f64> = fits.iter().map(|t| effect.to_report_units(k, t[c])).collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (values.len() - 1) as f64).sqrt();
        eprintln!("{name}: predicted {predicted:.3e}, spread {spread:.3e}");
        assert!((predicted / spread - 1.0).abs() <= 0.2, "{name}: predicted {predicted}, spread of fits {spread}");
        checked += 1;
    }
    assert!(checked >= 8, "{checked} parameters checked");
}

#[test]
fn effects_no_choice_of_the_candidates_makes_eligible_are_left_out_with_the_reason() {
    // Joint 1 within ±20° in every candidate (a cell that never turns the base far): no choice of them
    // gives its gear ratio the quarter of its travel or its cyclic error the half revolution the
    // diagnosis needs, so the plan is not made for them; nor for joint 2's cyclic error (its travel is
    // 200°, the candidates keep 10 % inside each limit: 160° < half a revolution); joint 2's gear ratio,
    // which the candidates cover, stays.
    let robot = irb140();
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let joints: Vec<Vec<f64>> = (0..400)
        .map(|_| {
            let mut q = thermokin_testdata::random_q(robot.chain(), &mut rng);
            q[0] = rand::Rng::random_range(&mut rng, -20f64.to_radians()..20f64.to_radians());
            q
        })
        .collect();
    let pool = Candidates::new(&robot, joints, vec![]).unwrap();
    let p = plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(25), ..Params::default() }).unwrap();
    let left: Vec<&str> = p.left_out.iter().map(|l| l.effect.as_str()).collect();
    assert_eq!(left, ["joint_scale[1]", "periodic[1]", "periodic[2]"], "{:?}", p.left_out);
    assert!(
        p.left_out[0].reason.starts_with("joint 1 spans") && p.left_out[0].reason.contains("needs 90°"),
        "{:?}",
        p.left_out
    );
    assert!(!p.effects.iter().any(|e| e == "joint_scale[1]" || e == "periodic[1]"), "{:?}", p.effects);
    assert!(p.effects.iter().any(|e| e == "joint_scale[2]"), "{:?}", p.effects);
    assert!(p.text().contains("Not planned for"), "{}", p.text());
}

/// A robot file without masses: by default the plan carries no lateral compliance; with
/// `Lateral::Joints` (as `diagnose --lateral joints`) it plans for each loaded joint's, its loads lumped.
#[test]
fn the_plan_carries_the_lateral_compliances_the_diagnosis_will_offer() {
    let robot = irb140().with_masses(vec![None; 6]).unwrap();
    let pool = Candidates::sampled(&robot, 400, 17, None).unwrap();
    let lateral =
        |p: &thermokin_planner::Plan| p.effects.iter().filter(|e| e.starts_with("lateral_compliance")).count();
    let by_default = plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(60), ..Params::default() }).unwrap();
    assert_eq!(lateral(&by_default), 0, "{:?}", by_default.effects);
    let params =
        Params { poses: Poses::Exactly(60), lateral: thermokin_identify::Lateral::Joints, ..Params::default() };
    let joints = plan(&robot, &pool, &[], &params).unwrap();
    assert!(joints.effects.iter().any(|e| e == "lateral_compliance[2] (no masses)"), "{:?}", joints.effects);
}

/// An IRB 140 on an 800 mm lift: the plan carries the slide's scale, its guide's straightness and its
/// column's lateral compliance (on the file's masses, or lumped from the file without them), and its
/// poses reach both ends of the stroke (a tilt and a bow growing with the extension are seen between its
/// ends, as a scale is).
#[test]
fn a_lifts_plan_carries_its_straightness_and_spans_the_stroke() {
    let text = thermokin_testdata::lifted_irb140_toml("");
    let robot = thermokin_io::parse_robot_toml("lift.toml".as_ref(), &text).unwrap();
    let massless = robot.clone().with_masses(vec![None; 7]).unwrap();
    let pool = Candidates::sampled(&massless, 600, 23, None).unwrap();
    let params = Params { poses: Poses::Exactly(40), ..Params::default() };
    let without = plan(&massless, &pool, &[], &params).unwrap();
    assert!(without.effects.iter().any(|e| e == "lateral_compliance[1] (no masses)"), "{:?}", without.effects);
    let pool = Candidates::sampled(&robot, 600, 23, None).unwrap();
    let p = plan(&robot, &pool, &[], &params).unwrap();
    for effect in ["straightness[1]", "joint_scale[1]", "lateral_compliance[1]"] {
        assert!(p.effects.iter().any(|e| e == effect), "{:?}", p.effects);
    }
    let (lo, hi) = p
        .poses
        .iter()
        .map(|x| x.joints_rad[0])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| (l.min(d), h.max(d)));
    // The plan takes the ends the candidates offer (within a tenth of their span).
    let (plo, phi) = pool_range(&pool);
    eprintln!("stroke planned {lo:.0} … {hi:.0} mm of the candidates' {plo:.0} … {phi:.0}");
    assert!(lo - plo < 0.1 * (phi - plo) && phi - hi < 0.1 * (phi - plo), "{lo} … {hi} of {plo} … {phi}");
}

fn pool_range(pool: &Candidates) -> (f64, f64) {
    pool.joints().iter().map(|q| q[0]).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), d| (l.min(d), h.max(d)))
}

/// The prediction criterion (the default): the mean predicted variance after each pose in measuring order
/// never increases, the plan's promise at the poses of use is below random draws', and `Poses::Auto`
/// stops where it says: the next pose's gain below a test's resolution, no sooner than the rows reach the
/// free parameters' count, and no later than the count it would stop at with one pose more allowed.
#[test]
fn a_plan_for_prediction_lowers_the_predicted_error_and_stops_where_a_test_could_not_tell() {
    let robot = irb140();
    let pool = Candidates::sampled(&robot, 400, 11, None).unwrap();
    let p = plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(25), ..Params::default() }).unwrap();
    assert_eq!(p.criterion, Criterion::Prediction);
    assert!(p.criterion_by_pose.windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-9)), "{:?}", p.criterion_by_pose);
    let promise = &p.promise;
    assert!(promise.planned_rms_mm < promise.random_rms_mm.unwrap(), "{promise:?}");
    // At noise σ with nothing to fit the held-out RMS would be σ√3; the model's share only adds to it.
    assert!(promise.planned_rms_mm > promise.noise_mm * 3f64.sqrt());
    let auto = Params { poses: Poses::Auto { at_most: 400 }, ..Params::default() };
    let a = plan(&robot, &pool, &[], &auto).unwrap();
    let rule = a.count.clone().unwrap();
    let [gain, resolution] = rule.stopped.expect("stopped before every candidate");
    assert!(gain < resolution, "{rule:?}");
    let free = p.parameters.len();
    assert!(3 * a.poses.len() >= free, "{} poses for {free} parameters", a.poses.len());
    // The count is the greedy choice's: asked for that many exactly, the same poses (before exchanges
    // the two runs share every step), and the promise of one pose more lowers the RMS by `gain`.
    let exactly =
        plan(&robot, &pool, &[], &Params { poses: Poses::Exactly(a.poses.len()), ..Params::default() }).unwrap();
    let same = |x: &thermokin_planner::Plan| {
        let mut c: Vec<usize> = x.poses.iter().map(|p| p.candidate).collect();
        c.sort();
        c
    };
    assert_eq!(same(&a), same(&exactly));
}
