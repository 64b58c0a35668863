"""FK of the seven public URDFs against Pinocchio (an independent implementation, from the package
index), on seeded configurations; and the calibrated robot a diagnosis exports, loaded by Pinocchio,
against our FK of the same robot."""

import numpy as np
import pytest

import thermokin

pin = pytest.importorskip("pinocchio")

# (file, tip link): the end-effector link of each description (the chain's last link before tools or
# fingers).
URDFS = [
    ("abb_irb140.urdf", "tool0"),
    ("ur5.urdf", "tool0"),
    ("ur10.urdf", "tool0"),
    ("panda.urdf", "panda_hand_tcp"),
    ("xarm7.urdf", "link_eef"),
    ("kinova.urdf", "j2s6s200_end_effector"),
    ("z1.urdf", "gripperStator"),
]

# Both sides evaluate the same products of rigid transforms in double precision; over ~1 m of arm the
# rounding is ~1e-13 m. 1e-9 mm (1e-12 m) leaves room for a different order of multiplication and
# nothing for a wrong axis, origin or sign (those show at ≥ 1e-3 mm).
TOL_MM = 1e-9
TOL_ROT = 1e-12


def pinocchio_q(model, q_by_name_rad):
    """Pinocchio's configuration vector: the joints we drive at their values, every other joint (the
    fingers) at its neutral value; a continuous joint takes (cos, sin)."""
    q = pin.neutral(model)
    for name, value in q_by_name_rad.items():
        joint = model.joints[model.getJointId(name)]
        if joint.nq == 2:
            q[joint.idx_q : joint.idx_q + 2] = [np.cos(value), np.sin(value)]
        else:
            q[joint.idx_q] = value
    return q


def pinocchio_fk(model, q_by_name_rad, tip):
    """The tip link's placement (metres) by Pinocchio."""
    data = model.createData()
    pin.forwardKinematics(model, data, pinocchio_q(model, q_by_name_rad))
    pin.updateFramePlacements(model, data)
    return data.oMf[model.getFrameId(tip, pin.BODY)]


def seeded_configurations(robot, count, seed):
    rng = np.random.default_rng(seed)
    limits = robot.limits_deg
    lo = np.where(np.isfinite(limits[:, 0]), limits[:, 0], -180.0)
    hi = np.where(np.isfinite(limits[:, 1]), limits[:, 1], 180.0)
    return rng.uniform(lo, hi, size=(count, robot.dof))


@pytest.mark.parametrize("name,tip", URDFS)
def test_fk_equals_pinocchio_on_every_public_urdf(root, name, tip):
    path = root / "fixtures" / "urdf" / name
    robot = thermokin.Robot.from_file(path, tip=tip)
    model = pin.buildModelFromUrdf(str(path))
    q_deg = seeded_configurations(robot, 50, seed=7)
    ours = robot.fk(q_deg)
    for q, T in zip(q_deg, ours):
        theirs = pinocchio_fk(model, dict(zip(robot.joint_names, np.radians(q))), tip)
        np.testing.assert_allclose(T[:3, 3], theirs.translation * 1000.0, rtol=0, atol=TOL_MM)
        np.testing.assert_allclose(T[:3, :3], theirs.rotation, rtol=0, atol=TOL_ROT)


@pytest.mark.parametrize("name,tip", URDFS)
def test_jacobian_equals_pinocchio_in_the_base_frame(root, name, tip):
    """Our geometric Jacobian (mm per rad; rad per rad) against Pinocchio's frame Jacobian in
    LOCAL_WORLD_ALIGNED (m per rad); a continuous joint's column is its one velocity."""
    path = root / "fixtures" / "urdf" / name
    robot = thermokin.Robot.from_file(path, tip=tip)
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    for q in seeded_configurations(robot, 10, seed=11):
        qp = pinocchio_q(model, dict(zip(robot.joint_names, np.radians(q))))
        J = pin.computeFrameJacobian(model, data, qp, model.getFrameId(tip, pin.BODY), pin.LOCAL_WORLD_ALIGNED)
        cols = [model.joints[model.getJointId(n)].idx_v for n in robot.joint_names]
        theirs = J[:, cols]
        ours = robot.jacobian(q)
        np.testing.assert_allclose(ours[:3], theirs[:3] * 1000.0, rtol=0, atol=1e-9)
        np.testing.assert_allclose(ours[3:], theirs[3:], rtol=0, atol=1e-12)


def test_the_exported_calibrated_urdf_loads_in_pinocchio_with_the_same_fk(root, tmp_path):
    """A diagnosis of a simulated set with geometric effects; its calibrated robot written as URDF and
    read by Pinocchio: the same FK as ours of the calibrated robot (what URDF can hold: geometry)."""
    robot = thermokin.Robot.from_file(root / "configs" / "irb140.toml")
    data = thermokin.simulate(
        robot, ["joint_offset:2=0.05", "link_deviation:3=0.3,-0.2,0.1,0.01,0.02,-0.01"], poses=160, minutes=0
    )
    report = thermokin.diagnose(robot, data, noise_mm=0.005)
    calibrated = report.calibrated
    assert calibrated.beyond_urdf == [], calibrated.beyond_urdf
    # The calibration moved the robot (the test would pass vacuously on the nominal one otherwise).
    moved = np.abs(calibrated.fk([0, 30, 10, 0, -40, 0])[:3, 3] - robot.fk([0, 30, 10, 0, -40, 0])[:3, 3]).max()
    assert moved > 0.05, (report.effects, moved)
    path = tmp_path / "calibrated.urdf"
    calibrated.save(path)
    model = pin.buildModelFromUrdf(str(path))
    names = calibrated.joint_names
    tip = model.frames[len(model.frames) - 1].name
    q_deg = seeded_configurations(calibrated, 30, seed=3)
    ours = calibrated.fk(q_deg)
    for q, T in zip(q_deg, ours):
        theirs = pinocchio_fk(model, dict(zip(names, np.radians(q))), tip)
        # The URDF holds the calibrated geometry in metres printed with enough digits for 1e-9 m.
        np.testing.assert_allclose(T[:3, 3], theirs.translation * 1000.0, rtol=0, atol=1e-6)
        np.testing.assert_allclose(T[:3, :3], theirs.rotation, rtol=0, atol=1e-9)
