//! Time profiles: nominal at t = 0, the linear profile's half-way point, plateau or not, bad parameters.

use thermokin_deform::{AfterStabilization, DeformError, DeviationTable, TemperatureLog, TimeProfile};

fn table() -> DeviationTable {
    DeviationTable::from_joint_rows(vec![thermokin_testdata::error_mm_deg([1.0, -2.0, 3.0, 0.5, -0.25, 1.0]); 3])
}

fn log() -> TemperatureLog {
    TemperatureLog {
        times_min: vec![0.0, 60.0, 180.0],
        sensors: vec![("a".into(), vec![20.0, 26.0, 30.0]), ("b".into(), vec![21.0, 21.0, 25.0])],
    }
}

fn all_time_dependent() -> Vec<TimeProfile> {
    vec![
        TimeProfile::paper_linear(),
        TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing },
        TimeProfile::Exponential { tau_min: 45.0 },
        TimeProfile::Cubic { coefficients: [0.01, -1e-5, 2e-8] },
        TimeProfile::Temperature { log: log(), sensors: vec!["a".into(), "b".into(), "a".into()], reference_c: None },
    ]
}

#[test]
fn every_time_dependent_profile_is_nominal_at_zero() {
    for p in all_time_dependent() {
        assert!(p.table_at(&table(), 0.0).unwrap().is_zero(), "{p:?}");
    }
    // The static profile is the full table at every time.
    assert_eq!(TimeProfile::Static.table_at(&table(), 0.0).unwrap(), table());
    assert_eq!(TimeProfile::Static.table_at(&table(), 500.0).unwrap(), table());
}

#[test]
fn linear_at_90_minutes_is_half_the_table() {
    let half = TimeProfile::paper_linear().table_at(&table(), 90.0).unwrap();
    assert_eq!(half, table().scaled(0.5));
    // Plateau after 180 min; the authors' transient file keeps growing (200 min → 10/9).
    assert_eq!(TimeProfile::paper_linear().table_at(&table(), 200.0).unwrap(), table());
    let grow = TimeProfile::Linear { stabilization_min: 180.0, after: AfterStabilization::KeepGrowing };
    let f = grow.row_factors(200.0, 3).unwrap();
    assert!((f.joints[0] - 200.0 / 180.0).abs() < 1e-15);
}

#[test]
fn exponential_cubic_and_temperature_values() {
    let e = TimeProfile::Exponential { tau_min: 45.0 }.row_factors(45.0, 3).unwrap();
    assert!((e.joints[0] - (1.0 - (-1f64).exp())).abs() < 1e-15);
    let c = TimeProfile::Cubic { coefficients: [0.01, -1e-5, 2e-8] }.row_factors(100.0, 3).unwrap();
    assert!((c.joints[0] - (1.0 - 0.1 + 0.02)).abs() < 1e-12);
    let p =
        TimeProfile::Temperature { log: log(), sensors: vec!["a".into(), "b".into(), "a".into()], reference_c: None };
    // Sensor a at 120 min: 26 + (30 − 26)/2 = 28 °C, rise 8 K; sensor b: 21 + 2 = 23 °C, rise 2 K.
    let f = p.row_factors(120.0, 3).unwrap();
    assert_eq!(f.joints, vec![8.0, 2.0, 8.0]);
    assert_eq!((f.base, f.tool), (8.0, 8.0));
    assert!(matches!(p.row_factors(181.0, 3), Err(DeformError::BadTime { .. })));
}

#[test]
fn bad_profiles_and_times() {
    let bad = [
        TimeProfile::Linear { stabilization_min: -180.0, after: AfterStabilization::Plateau },
        TimeProfile::Linear { stabilization_min: f64::NAN, after: AfterStabilization::Plateau },
        TimeProfile::Exponential { tau_min: 0.0 },
        TimeProfile::Cubic { coefficients: [f64::INFINITY, 0.0, 0.0] },
        TimeProfile::Temperature { log: log(), sensors: vec!["a".into(), "zzz".into(), "a".into()], reference_c: None },
        TimeProfile::Temperature { log: log(), sensors: vec!["a".into()], reference_c: None },
    ];
    for p in bad {
        assert!(matches!(p.row_factors(10.0, 3), Err(DeformError::BadProfile { .. })), "{p:?}");
    }
    for t in [-1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(TimeProfile::Static.row_factors(t, 3), Err(DeformError::BadTime { .. })));
    }
}

#[test]
fn profiles_are_plain_serde_values() {
    // The TOML form a user writes.
    let p: TimeProfile = toml::from_str("kind = \"linear\"\nstabilization_min = 180.0\nafter = \"plateau\"\n").unwrap();
    assert_eq!(p, TimeProfile::paper_linear());
    let p: TimeProfile = toml::from_str("kind = \"exponential\"\ntau_min = 40.0\n").unwrap();
    assert_eq!(p, TimeProfile::Exponential { tau_min: 40.0 });
    assert!(toml::from_str::<TimeProfile>("kind = \"exponential\"\ntau = 40.0\n").is_err());
}

#[test]
fn temperature_profile_without_sensor_names_follows_the_mean_rise() {
    let p = TimeProfile::Temperature { log: log(), sensors: Vec::new(), reference_c: None };
    // At 120 min: sensor a 28 °C (+8 K), sensor b 23 °C (+2 K): mean rise 5 K on every row.
    let f = p.row_factors(120.0, 3).unwrap();
    assert_eq!(f.joints, vec![5.0; 3]);
    assert_eq!((f.base, f.tool), (5.0, 5.0));
    assert!(p.table_at(&table(), 0.0).unwrap().is_zero());
}
