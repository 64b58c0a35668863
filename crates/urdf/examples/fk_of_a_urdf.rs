//! Forward kinematics of a URDF: the tool pose at the joint values given in degrees.
//!
//! ```text
//! cargo run --example fk_of_a_urdf -p thermokin-urdf -- [ROBOT.urdf TIP_LINK Q1,Q2,…]
//! ```
//! Without arguments: the UR10 of `fixtures/urdf/ur10.urdf` to `tool0` at 0,-90,90,0,90,0.

use std::error::Error;

use thermokin_chain::{units, xyz_angles};
use thermokin_urdf::{ImportOptions, import_urdf};

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let default_urdf = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/urdf/ur10.urdf").to_string();
    let path = args.first().cloned().unwrap_or(default_urdf);
    let tip = args.get(1).cloned().unwrap_or_else(|| "tool0".into());
    let joints_deg: Vec<f64> = match args.get(2) {
        Some(list) => list.split(',').map(str::parse).collect::<Result<_, _>>()?,
        None => vec![0.0, -90.0, 90.0, 0.0, 90.0, 0.0],
    };
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{path}: {e}"))?;
    let options = ImportOptions { tip: Some(tip.clone()), ..ImportOptions::default() };
    let robot = import_urdf(&text, &path, &options)?.robot;
    if joints_deg.len() != robot.chain().dof() {
        return Err(format!("{} joint values for {} joints", joints_deg.len(), robot.chain().dof()).into());
    }
    // Degrees at the edge, radians inside (a prismatic joint would stay in mm: none here is).
    let q: Vec<f64> = joints_deg.iter().map(|&d| units::radians(d)).collect();
    let base_from_tool = robot.chain().tool_pose(&q)?;
    let p = base_from_tool.translation.vector;
    let angles = xyz_angles(base_from_tool.rotation.to_rotation_matrix().matrix()).map(units::degrees);
    println!("{} ({} joints), {tip} at {joints_deg:?}°:", robot.name(), robot.chain().dof());
    println!("  position  {:.4} {:.4} {:.4} mm", p.x, p.y, p.z);
    println!("  X-Y-Z Euler {:.4} {:.4} {:.4}°", angles.x, angles.y, angles.z);
    Ok(())
}
