//! The exported URDF against the rules a URDF consumer applies (`check_urdf`, MoveIt, ros2_control):
//! parsed by urdf-rs (an independent reader), a valid robot name, one tree from one root, every moving
//! joint with a positive velocity and effort, inertials with positive mass and a positive-definite
//! tensor; and the re-import carries masses, ratings and FK.

use std::collections::{HashMap, HashSet};

use thermokin_chain::{JointRatings, LinkMass};
use thermokin_testdata::urdf;
use thermokin_urdf::{DEFAULT_EFFORT, ImportOptions, export_robot, import_urdf, urdf_name};

#[test]
fn exported_urdf_passes_the_consumers_rules_and_round_trips() {
    for (file, tip) in
        [("ur5.urdf", Some("tool0")), ("panda.urdf", Some("panda_hand_tcp")), ("abb_irb140.urdf", Some("tool0"))]
    {
        let text = std::fs::read_to_string(urdf(file)).unwrap();
        let options = ImportOptions { base: None, tip: tip.map(str::to_string) };
        let robot = import_urdf(&text, file, &options).unwrap().robot;
        let n = robot.chain().dof();
        // Masses everywhere; ratings on every other joint (the rest take the documented defaults).
        let masses: Vec<Option<LinkMass>> = (0..n)
            .map(|i| {
                Some(LinkMass { mass_kg: 1.0 + i as f64, com_mm: nalgebra::Vector3::new(10.0, -5.0, 20.0 * i as f64) })
            })
            .collect();
        let ratings: Vec<JointRatings> = (0..n)
            .map(|i| {
                if i % 2 == 0 {
                    JointRatings { velocity: Some(2.0), effort: Some(150.0) }
                } else {
                    JointRatings::default()
                }
            })
            .collect();
        let name = format!("{} with spaces & symbols", robot.name());
        let described = robot.clone().renamed(name.clone()).with_masses(masses.clone()).unwrap();
        let xml = export_robot(&described.with_ratings(ratings.clone()).unwrap());
        let parsed =
            urdf_rs::read_from_string(&xml).unwrap_or_else(|e| panic!("{file}: urdf-rs refuses the export: {e}"));

        assert!(parsed.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'), "{}", parsed.name);
        assert_eq!(parsed.name, urdf_name(&name));
        // One tree: unique names, every joint's links exist, each link has at most one parent, one root.
        let links: HashSet<&str> = parsed.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(links.len(), parsed.links.len(), "{file}: duplicate link names");
        let joints: HashSet<&str> = parsed.joints.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(joints.len(), parsed.joints.len(), "{file}: duplicate joint names");
        let mut parent_of: HashMap<&str, &str> = HashMap::new();
        for j in &parsed.joints {
            assert!(
                links.contains(j.parent.link.as_str()) && links.contains(j.child.link.as_str()),
                "{file}: {}",
                j.name
            );
            assert!(parent_of.insert(j.child.link.as_str(), j.parent.link.as_str()).is_none(), "{file}: two parents");
        }
        let roots: Vec<&&str> = links.iter().filter(|l| !parent_of.contains_key(**l)).collect();
        assert_eq!(roots.len(), 1, "{file}: roots {roots:?}");
        // Moving joints: positive velocity and effort (0 reads as "cannot move" to a planner).
        for j in parsed.joints.iter().filter(|j| j.joint_type != urdf_rs::JointType::Fixed) {
            assert!(j.limit.velocity > 0.0 && j.limit.effort > 0.0, "{file}: {} has {:?}", j.name, j.limit);
            if j.joint_type == urdf_rs::JointType::Revolute {
                assert!(j.limit.lower < j.limit.upper, "{file}: {}", j.name);
            }
        }
        // Inertials: positive mass, positive-definite diagonal tensor.
        let with_mass: Vec<_> = parsed.links.iter().filter(|l| l.inertial.mass.value > 0.0).collect();
        assert_eq!(with_mass.len(), n, "{file}");
        for l in with_mass {
            let i = &l.inertial.inertia;
            assert!(i.ixx > 0.0 && i.iyy > 0.0 && i.izz > 0.0, "{file}: {}", l.name);
        }
        // Re-import: the same masses, ratings (defaults where none were given) and FK.
        let back = import_urdf(&xml, "exported", &ImportOptions::default()).unwrap().robot;
        for (k, (b, m)) in back.masses().iter().zip(&masses).enumerate() {
            let (b, m) = (b.unwrap(), m.unwrap());
            assert!((b.mass_kg - m.mass_kg).abs() < 1e-9, "{file}: joint {k} mass");
            assert!((b.com_mm - m.com_mm).norm() < 1e-6, "{file}: joint {k} com {:?} vs {:?}", b.com_mm, m.com_mm);
        }
        for (k, (b, r)) in back.ratings().iter().zip(&ratings).enumerate() {
            assert_eq!(b.effort, Some(r.effort.unwrap_or(DEFAULT_EFFORT)), "{file}: joint {k}");
            assert!(b.velocity.is_some(), "{file}: joint {k}");
        }
        let q: Vec<f64> = (0..n).map(|i| 0.3 - 0.1 * i as f64).collect();
        let d = back.chain().tool_pose(&q).unwrap().translation.vector
            - robot.chain().tool_pose(&q).unwrap().translation.vector;
        assert!(d.norm() < 1e-9, "{file}: {d:?}");
    }
}
