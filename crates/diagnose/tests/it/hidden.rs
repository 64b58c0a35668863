//! Data generated from one hidden effect at a time: the diagnosis, told nothing, must name the effect
//! and the joint; the held-out RMS must shrink at least 5× and end within 1.5× of the noise.

use thermokin_diagnose::{
    Base, Config, DriftShape, Effect, EffectKind, HiddenEffect, SimulationConfig, diagnose, simulate,
};
use thermokin_testdata::workspace;

fn base() -> Base {
    let r = thermokin_io::read_robot(&workspace("configs/irb140.toml")).unwrap();
    Base { chain: r.chain, masses: r.masses }
}

const NOISE: f64 = 0.005;

fn deg(v: f64) -> f64 {
    v.to_radians()
}

fn check(hidden: HiddenEffect, expect_kind: &str, expect_joint: Option<usize>) {
    let b = base();
    let data = simulate(
        &b,
        std::slice::from_ref(&hidden),
        &SimulationConfig { noise_mm: NOISE, ..SimulationConfig::default() },
    )
    .unwrap();
    let report = diagnose(&b, &data, None, &Config::default()).unwrap();
    let main = report
        .effects
        .first()
        .unwrap_or_else(|| panic!("{}: no effect found; nominal {:?}", hidden.effect.label(), report.nominal));
    let noise_rms = NOISE * 3f64.sqrt();
    let before = report.nominal.heldout_rms_mm;
    let after = report.additive.last().unwrap().stats.heldout_rms_mm;
    eprintln!(
        "{}: found {:?}; held-out RMS {before:.4} → {after:.4} mm (noise {noise_rms:.4}); additive {:?}",
        hidden.effect.label(),
        report.effects.iter().map(|e| e.label.clone()).collect::<Vec<_>>(),
        report
            .additive
            .iter()
            .map(|r| (r.model.clone(), (r.stats.heldout_rms_mm * 1e4).round() / 1e4))
            .collect::<Vec<_>>()
    );
    eprintln!("  parameters {:?}", main.parameters);
    assert_eq!(main.effect, expect_kind, "{}", hidden.effect.label());
    assert_eq!(main.joints, expect_joint.map(|j| vec![j]).unwrap_or_default(), "{}", hidden.effect.label());
    assert!(before / after >= 5.0, "{}: shrank only {:.2}×", hidden.effect.label(), before / after);
    assert!(after <= 1.5 * noise_rms, "{}: ends at {after:.4} mm, noise {noise_rms:.4}", hidden.effect.label());
}

#[test]
fn finds_a_base_misalignment() {
    let v = vec![0.5, -0.3, 0.4, deg(0.02), deg(-0.01), deg(0.015)];
    check(HiddenEffect { effect: Effect::global(EffectKind::BaseFrame), values: v }, "base_frame", None);
}

#[test]
fn finds_a_tool_error() {
    check(
        HiddenEffect { effect: Effect::global(EffectKind::ToolFrame), values: vec![0.3, 0.2, -0.4] },
        "tool_frame",
        None,
    );
}

#[test]
fn finds_a_joint_offset() {
    check(
        HiddenEffect { effect: Effect::at(EffectKind::JointOffset, 1), values: vec![deg(0.05)] },
        "joint_offset",
        Some(2),
    );
}

#[test]
fn finds_a_link_deviation() {
    // Joint 3 turns about Y: its Δθy would be a joint offset, so the hidden deviation has none.
    let v = vec![0.3, -0.2, 0.25, deg(0.02), 0.0, deg(0.015)];
    check(HiddenEffect { effect: Effect::at(EffectKind::LinkDeviation, 2), values: v }, "link_deviation", Some(3));
}

#[test]
fn finds_gravity_compliance() {
    check(
        HiddenEffect { effect: Effect::at(EffectKind::JointCompliance, 1), values: vec![2e-5] },
        "joint_compliance",
        Some(2),
    );
}

#[test]
fn finds_a_linear_thermal_drift() {
    let v = vec![0.4, 0.0, -0.3, 0.0, deg(0.0), deg(0.02)];
    check(
        HiddenEffect { effect: Effect::at(EffectKind::ThermalDrift(DriftShape::Linear), 1), values: v },
        "thermal_drift",
        Some(2),
    );
}

#[test]
fn finds_an_exponential_thermal_drift() {
    let v = vec![0.0, 0.3, -0.4, deg(0.02), 0.0, 0.0, 50.0];
    check(
        HiddenEffect { effect: Effect::at(EffectKind::ThermalDrift(DriftShape::Exponential), 2), values: v },
        "thermal_drift",
        Some(3),
    );
}

#[test]
fn an_effect_on_a_joint_the_robot_lacks_is_an_error_not_a_panic() {
    use thermokin_diagnose::{Base, Effect, EffectKind, HiddenEffect, SimulationConfig, simulate};
    let base = Base { chain: thermokin_testdata::irb140_table9(), masses: vec![None; 6] };
    for effect in [
        Effect::at(EffectKind::JointOffset, 8),
        Effect::global(EffectKind::LinkDeviation),
        Effect::at(EffectKind::BaseFrame, 1),
    ] {
        let hidden = [HiddenEffect { effect, values: vec![0.0; effect.len()] }];
        let r = simulate(&base, &hidden, &SimulationConfig { poses: 10, ..SimulationConfig::default() });
        assert!(r.is_err(), "{effect:?} was accepted");
    }
}
