"""The Python API against the command line (an independent front end on the same files), against
properties (batch = loop, FK∘IK = identity, round trips), and on bad input (the field named)."""

import json
import math
import re
import subprocess

import numpy as np
import pytest

import thermokin
from thermokin import InputError, MissingFileError, ThermokinError

Q = [0, 30, 10, 0, -40, 0]
SEED = [0, 20, 20, 0, -45, 0]


@pytest.fixture(scope="module")
def irb140(root):
    return thermokin.Robot.from_file(root / "configs" / "irb140.toml")


def configurations(robot, n, seed):
    rng = np.random.default_rng(seed)
    lim = robot.limits_deg
    return rng.uniform(lim[:, 0] * 0.8, lim[:, 1] * 0.8, size=(n, robot.dof))


def test_robot_facts(irb140):
    assert irb140.dof == 6
    assert irb140.joint_names == ["A1", "A2", "A3", "A4", "A5", "A6"]
    assert irb140.limits_deg.shape == (6, 2)
    assert np.all(irb140.limits_deg[:, 0] < irb140.limits_deg[:, 1])
    assert irb140.is_plain
    assert irb140.branches == {}


def test_a_urdf_trees_other_chains_are_its_branches(root):
    # The Panda's hand carries two fingers beside the tool point: the left's slide is a branch from the
    # last link; the right one mimics it (a mimic joint cuts a branch, leaving it none).
    panda = thermokin.Robot.from_file(root / "fixtures" / "urdf" / "panda.urdf", tip="panda_hand_tcp")
    assert panda.branches == {"panda_leftfinger": (7, ["panda_finger_joint1"])}


def test_fk_equals_the_command_line(irb140, root, cli):
    out = subprocess.run(
        [cli, "fk", "--robot", "configs/irb140.toml", "--joints", ",".join(map(str, Q)), "--json"],
        cwd=root, check=True, capture_output=True, text=True,
    )
    theirs = json.loads(out.stdout)
    T = irb140.fk(Q)
    # The CLI prints positions rounded to 1e-10 mm and matrix entries to 1e-13.
    np.testing.assert_allclose(T[:3, 3], theirs["position_mm"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(T[:3, :3], theirs["rotation"], rtol=0, atol=1e-13)
    np.testing.assert_array_equal(T[3], [0, 0, 0, 1])


def test_batches_equal_the_loop(irb140):
    qs = configurations(irb140, 64, seed=1)
    np.testing.assert_array_equal(irb140.fk(qs), np.stack([irb140.fk(q) for q in qs]))
    np.testing.assert_array_equal(irb140.jacobian(qs), np.stack([irb140.jacobian(q) for q in qs]))
    poses = irb140.fk(qs)
    batch = irb140.ik(poses, seed=SEED)
    for k, pose in enumerate(poses[:16]):
        one = irb140.ik(pose, seed=SEED)
        assert one.status == batch.status[k]
        # Restart generators are seeded by the target's index: without restarts the paths are equal.
        if one.iterations == batch.iterations[k]:
            np.testing.assert_array_equal(one.q, batch.q[k])


def test_ik_answers_are_verified_by_fk(irb140):
    qs = configurations(irb140, 200, seed=2)
    targets = irb140.fk(qs)
    result = irb140.ik(targets, seed=SEED)
    assert result.q.shape == (200, 6)
    assert len(result.status) == 200
    converged = np.asarray(result.converged)
    assert converged.mean() > 0.95, result.status
    reached = irb140.fk(result.q[converged])
    # FK∘IK = identity: the solver's tolerance is 1e-9 mm (and its rotation counterpart).
    np.testing.assert_allclose(reached[:, :3, 3], targets[converged][:, :3, 3], rtol=0, atol=1e-8)
    np.testing.assert_allclose(reached[:, :3, :3], targets[converged][:, :3, :3], rtol=0, atol=1e-10)
    assert np.all(result.position_error_mm[converged] <= 1e-8)


def test_position_only_and_unreachable_targets_are_records_not_errors(irb140):
    r = irb140.ik([[600, 0, 400], [5000, 0, 0]], position_only=True, seed=SEED)
    assert r.status[0] == "Converged"
    assert r.status[1] == "Unreachable"
    assert not r.converged[1]


def test_jacobian_matches_finite_differences(irb140):
    # Units: linear rows mm per radian; a central difference in degrees converted to radians.
    q = np.array(Q, dtype=float)
    J = irb140.jacobian(q)
    h = 1e-5  # degrees: truncation ~ h² of a 1 m lever, rounding ~ 1e-13 / h
    for k in range(6):
        dq = np.zeros(6)
        dq[k] = h
        dp = (irb140.fk(q + dq)[:3, 3] - irb140.fk(q - dq)[:3, 3]) / (2 * math.radians(h))
        np.testing.assert_allclose(J[:3, k], dp, rtol=0, atol=1e-5)


def test_dh_robot_matches_its_closed_form():
    # A planar two-link arm, classic DH: a1 = 300, a2 = 200 mm.
    robot = thermokin.Robot.from_dh([[300, 0, 0, 0], [200, 0, 0, 0]])
    for a, b in [(0, 0), (30, 45), (-90, 120)]:
        x = 300 * math.cos(math.radians(a)) + 200 * math.cos(math.radians(a + b))
        y = 300 * math.sin(math.radians(a)) + 200 * math.sin(math.radians(a + b))
        np.testing.assert_allclose(robot.fk([a, b])[:3, 3], [x, y, 0], rtol=0, atol=1e-10)


def test_simulate_writes_the_command_lines_set(irb140, root, cli, tmp_path):
    effects = ["joint_offset:2", "thermal_drift:3"]
    ours = tmp_path / "ours.csv"
    thermokin.simulate(irb140, effects, poses=60, minutes=120).to_csv(ours)
    theirs = tmp_path / "theirs.csv"
    args = [cli, "simulate", "--robot", "configs/irb140.toml", "--poses", "60", "--minutes", "120", "-o", theirs]
    for e in effects:
        args += ["--effect", e]
    subprocess.run(args, cwd=root, check=True, capture_output=True)
    assert ours.read_bytes() == theirs.read_bytes()


def test_measurements_round_trip_through_csv(irb140, tmp_path):
    m = thermokin.simulate(irb140, ["thermal_drift:2"], poses=30)
    path = tmp_path / "m.csv"
    m.to_csv(path)
    back = thermokin.Measurements.from_csv(path, irb140)
    assert len(back) == 30
    # The writer prints 1e-9 mm / degree digits.
    np.testing.assert_allclose(back.q, m.q, rtol=0, atol=1e-9)
    np.testing.assert_allclose(back.xyz, m.xyz, rtol=0, atol=1e-9)
    again = thermokin.Measurements(irb140, back.q, back.xyz, time_min=back.time_min)
    np.testing.assert_array_equal(again.xyz, back.xyz)


def test_diagnose_equals_the_command_lines_json_on_the_real_ur10(root, cli, tmp_path):
    """Series C diagnosed with series B held out (other configurations), as the README's CLI does."""
    ur10 = root / "fixtures" / "urdf" / "ur10.urdf"
    series = root / "fixtures" / "real" / "ur10-ipa"
    robot = thermokin.Robot.from_file(ur10, tip="tool0")
    c = thermokin.Measurements.from_csv(series / "series_C.csv", robot)
    b = thermokin.Measurements.from_csv(series / "series_B.csv", robot)
    report = thermokin.diagnose(robot, c, holdout=b, noise_mm=0.01, frame="tracker", tool="unknown")
    out = tmp_path / "report.json"
    subprocess.run(
        [cli, "diagnose", "--robot", ur10, "--tip", "tool0", "--frame", "tracker", "--tool", "unknown",
         "--measurements", series / "series_C.csv", "--holdout", series / "series_B.csv", "--noise", "0.01",
         "--quiet", "--json", out],
        cwd=root, check=True, capture_output=True,
    )
    assert report.to_dict() == json.loads(out.read_text())
    assert report.effects, report.text
    assert report.text.startswith(report.text.splitlines()[0])
    # The folds chose a prior toward the nominal robot on C (2,773 poses): said as the JSON says it.
    assert report.shrinkage > 0.0
    assert report.shrinkage == report.to_dict()["shrinkage"]
    # The export is the model the report scored: its FK differs from the nominal robot's.
    calibrated = report.calibrated
    assert calibrated.dof == 6
    assert np.abs(calibrated.fk(c.q[:5])[:, :3, 3] - robot.fk(c.q[:5])[:, :3, 3]).max() > 0.01


def test_the_report_and_the_plan_as_pages(irb140):
    """The page `diagnose --html` and `plan --html` write, from a notebook: self-contained, its figures the
    report's."""
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05"], poses=120, minutes=0)
    report = thermokin.diagnose(irb140, data, noise_mm=0.005)
    page = report.html()
    assert page.startswith("<!DOCTYPE html>")
    assert "<script" not in page and not re.findall(r'(?:src|href)="[^"]*(?:http|//)', page)
    nested = report.to_dict()["nested"]["selected"]["heldout_mean_mm"]
    assert f'data-figure="nested.selected.heldout_mean_mm">{nested:.4f}<' in page
    assert "joint_offset[2]" in page
    plan = thermokin.plan(irb140, poses=10, samples=300)
    assert plan.html().startswith("<!DOCTYPE html>") and "10 poses for" in plan.html()


def test_diagnose_takes_arrays_as_it_takes_a_measurement_set(irb140):
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05", "thermal_drift:3"], poses=120, minutes=120)
    # The same numbers either way (degrees in both: `data.q` is the set's radians in degrees, which a
    # round trip may move by an ulp, so the set compared is built from those degrees too).
    same = thermokin.Measurements(irb140, data.q, data.xyz, time_min=data.time_min)
    from_set = thermokin.diagnose(irb140, same, noise_mm=0.005)
    from_arrays = thermokin.diagnose(irb140, data.q, data.xyz, time_min=data.time_min, noise_mm=0.005)
    assert from_arrays.to_dict() == from_set.to_dict()
    with pytest.raises(InputError, match="xyz"):
        thermokin.diagnose(irb140, data.q)
    with pytest.raises(InputError, match="xyz"):
        thermokin.diagnose(irb140, data, data.xyz)


def test_an_accelerometer_is_declared_by_its_link_and_its_columns_are_required(irb140):
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05"], poses=60, minutes=0)
    # The arrays carry no accelerometer columns: the declaration names the ones it needs.
    with pytest.raises(InputError, match="acc_top_x"):
        thermokin.diagnose(irb140, data, accelerometers={"acc_top": 0})
    # A link that a revolute joint below turns is refused, naming the joint.
    with pytest.raises(InputError, match="joint 1 below link 2"):
        thermokin.diagnose(irb140, data, accelerometers={"acc_top": 2})


def test_gross_errors_are_listed_by_line_and_left_out_unless_kept(irb140, tmp_path):
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05"], poses=120, minutes=0)
    xyz = data.xyz.copy()
    xyz[[10, 70]] += [[4.0, 0.0, 0.0], [0.0, -6.0, 2.0]]
    path = tmp_path / "m.csv"
    thermokin.Measurements(irb140, data.q, xyz).to_csv(path)
    report = thermokin.diagnose(irb140, thermokin.Measurements.from_csv(path, irb140), noise_mm=0.005)
    flagged = report.to_dict()["outliers"]
    # The header is line 1: rows 10 and 70 (0-based) are lines 12 and 72.
    assert [o["line"] for o in flagged] == [12, 72]
    assert report.to_dict()["outlier_screen"]["excluded"] is True
    assert report.effects[0] == "joint_offset[2]"
    kept = thermokin.diagnose(irb140, xyz=xyz, data=data.q, noise_mm=0.005, outliers="keep").to_dict()
    assert [o["measurement"] for o in kept["outliers"]] == [11, 71] and kept["outliers"][0]["line"] is None
    assert kept["outlier_screen"]["excluded"] is False
    with pytest.raises(InputError, match="outliers"):
        thermokin.diagnose(irb140, data, outliers="drop")


def test_compensate_writes_the_command_lines_joints(root, cli, tmp_path):
    scene = thermokin.Robot.from_file(root / "configs" / "irb140-scene.toml")
    table = root / "fixtures" / "paper" / "authors" / "deformations-case-study.csv"
    targets = root / "fixtures" / "paper" / "table12-targets.csv"
    run = thermokin.compensate(scene, targets, deformation=table, semantics="coppeliasim", seed=SEED)
    assert len(run) == 50
    assert run.status == ["Converged"] * 50
    assert run.position_error_mm.max() < 1e-8
    assert run.uncompensated_error_mm.max() > 1.0
    ours = tmp_path / "ours.csv"
    run.write(ours, format="joints")
    theirs = tmp_path / "theirs.csv"
    subprocess.run(
        [cli, "compensate", "--robot", "configs/irb140-scene.toml", "--semantics", "coppeliasim",
         "--deformation", table, "--targets", targets, "--seed", ",".join(map(str, SEED)),
         "--format", "joints", "--out", theirs],
        cwd=root, check=True, capture_output=True,
    )
    assert ours.read_bytes() == theirs.read_bytes()


def test_the_authors_transient_replay_writes_the_command_lines_file(root, cli, tmp_path):
    scene = thermokin.Robot.from_file(root / "configs" / "irb140-scene.toml")
    table = root / "fixtures" / "paper" / "authors" / "deformations-case-study.csv"
    targets = root / "fixtures" / "paper" / "table12-targets.csv"
    run = thermokin.compensate(
        scene, targets, deformation=table, semantics="coppeliasim", profile="linear-grow:180",
        accumulate="increments", seed=SEED,
    )
    assert len(run) == 201 * 50
    ours = tmp_path / "ours.csv"
    run.write(ours, format="long")
    theirs = tmp_path / "theirs.csv"
    subprocess.run(
        [cli, "compensate", "--robot", "configs/irb140-scene.toml", "--semantics", "coppeliasim",
         "--deformation", table, "--targets", targets, "--seed", ",".join(map(str, SEED)),
         "--profile", "linear-grow:180", "--accumulate", "increments", "--format", "long", "--out", theirs],
        cwd=root, check=True, capture_output=True,
    )
    assert ours.read_bytes() == theirs.read_bytes()


def test_the_warm_up_loop_from_measurements(irb140, tmp_path):
    """Diagnose a simulated warm-up, then compensate the next one with what it found (the paper's purpose)."""
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05", "thermal_drift:3=0.3,-0.2,0.25,0.004,0.006,0.01"], poses=240, minutes=180)
    report = thermokin.diagnose(irb140, data, noise_mm=0.005)
    assert any(e.startswith("thermal_drift") for e in report.effects), report.text
    warm = report.calibrated
    assert not warm.is_plain
    # A drifting robot has no pose without a time: an error that says so, not a cold pose.
    with pytest.raises(InputError) as e:
        warm.fk(Q)
    assert "time" in str(e.value), str(e.value)
    targets = np.array([[600, 0, 400, 0, 90, 0], [500, 200, 500, 0, 90, 0]], dtype=float)
    run = thermokin.compensate(warm, targets, time_min=60, seed=SEED)
    assert run.status == ["Converged", "Converged"]
    # The compensated joints put the warm robot (at minute 60) on the targets.
    reached = warm.fk(run.joints, time_min=60)
    np.testing.assert_allclose(reached[:, :3, 3], targets[:, :3], rtol=0, atol=1e-6)


def test_a_programs_sensor_columns_are_read_by_the_robots_names(root, tmp_path):
    # A robot whose joint-2 row turns with a sensor that is no temperature (an accelerometer's column, as
    # the diagnosis exports it): a targets file gives its reading under that name, and the compensated
    # joints put the robot at that reading on the target; without the column the reading is asked for.
    text = (root / "configs" / "irb140.toml").read_text()
    text += '\n[[drift]]\nrow = 2\nerror = [0, 0, 0, 0, 0.5, 0]\nper_kelvin = { sensors = ["acc_col_x"], reference_c = [0.1] }\n'
    path = tmp_path / "sensor.toml"
    path.write_text(text)
    robot = thermokin.Robot.from_file(path)
    targets = tmp_path / "program.csv"
    targets.write_text(",X,Y,Z,RX,RY,RZ,acc_col_x\nP1,600,0,400,0,90,0,1.1\nP2,500,200,500,0,90,0,0.4\n")
    run = thermokin.compensate(robot, targets, seed=SEED)
    assert run.status == ["Converged", "Converged"]
    for q, reading, goal in zip(run.joints, [1.1, 0.4], [[600, 0, 400], [500, 200, 500]]):
        reached = robot.fk(q, temps={"acc_col_x": reading})
        np.testing.assert_allclose(reached[:3, 3], goal, rtol=0, atol=1e-6)
    targets.write_text(",X,Y,Z,RX,RY,RZ\nP1,600,0,400,0,90,0\n")
    with pytest.raises(ThermokinError) as e:
        thermokin.compensate(robot, targets, seed=SEED)
    assert "acc_col_x" in str(e.value), str(e.value)


def test_dataframes_when_pandas_is_installed(irb140, root):
    pd = pytest.importorskip("pandas")
    scene = thermokin.Robot.from_file(root / "configs" / "irb140-scene.toml")
    run = thermokin.compensate(
        scene, root / "fixtures" / "paper" / "table12-targets.csv",
        deformation=root / "fixtures" / "paper" / "authors" / "deformations-case-study.csv", seed=SEED,
    )
    df = run.to_dataframe()
    assert isinstance(df, pd.DataFrame) and len(df) == 50 and "q6_deg" in df


@pytest.mark.parametrize(
    "call,kind,needle",
    [
        (lambda r: r.fk([0, 1, 2]), InputError, "q: expected shape (6,) or (N, 6)"),
        (lambda r: r.fk([0, 1, 2, 3, 4, float("nan")]), InputError, "q: value 5 is not finite"),
        (lambda r: r.fk([[0] * 6, [0, 0, 0, float("inf"), 0, 0]]), InputError, "q: row 1, value 3 is not finite"),
        (lambda r: r.ik(np.eye(3)), InputError, "pose: expected shape (4, 4)"),
        (lambda r: r.ik(np.diag([1.0, 2.0, 1.0, 1.0])), InputError, "pose"),
        (lambda r: r.fk(Q, time_min=float("nan")), InputError, "time_min"),
        (lambda r: thermokin.simulate(r, ["joint_offset:0"]), InputError, "joint_offset:0: joint `0`: joints are numbered from 1"),
        (lambda r: thermokin.simulate(r, ["no_such_effect"]), InputError, "unknown effect `no_such_effect`"),
        (lambda r: thermokin.simulate(r, poses=0), InputError, "poses must be at least 1"),
        (lambda r: thermokin.diagnose(r, thermokin.simulate(r, poses=40), folds=1), InputError, "folds"),
        (lambda r: thermokin.diagnose(r, thermokin.simulate(r, poses=40), frame="world"), InputError, "frame: unknown measurement frame `world` (use base, tracker)"),
        (lambda r: thermokin.compensate(r, [[600, 0, 400, 0, 90, 0]]), InputError, "nothing to compensate"),
        (lambda r: thermokin.compensate(r, [[600, 0, 400, 0, 90, 0]], deformation="nope.toml"), MissingFileError, "nope.toml"),
        (lambda r: r.deformed("fixtures/paper/deformations-case-study.toml", semantics="blender"), InputError, "semantics"),
        (lambda r: thermokin.compensate(r, [[600, 0, 400, 0, 90, 0]], deformation="fixtures/paper/deformations-case-study.toml", accumulate="increments"), InputError, 'accumulate="increments" needs a transient run'),
        (lambda r: thermokin.Robot.from_file("no/such/robot.toml"), MissingFileError, "no/such/robot.toml"),
    ],
)
def test_bad_inputs_raise_with_the_field_named(irb140, root, monkeypatch, call, kind, needle):
    monkeypatch.chdir(root)
    with pytest.raises(kind) as e:
        call(irb140)
    assert needle in str(e.value), str(e.value)
    assert isinstance(e.value, ThermokinError)


def test_a_malformed_file_names_its_line_and_field(irb140, tmp_path):
    bad = tmp_path / "m.csv"
    bad.write_text("q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,1,2,3\n0,0,0,0,0,zero,1,2,3\n")
    with pytest.raises(InputError) as e:
        thermokin.Measurements.from_csv(bad, irb140)
    assert f"{bad}:3" in str(e.value) and "q6" in str(e.value), str(e.value)
    robot = tmp_path / "r.toml"
    robot.write_text("[robot]\nname = 'x'\n[[joints]]\nname = 'a'\n")
    with pytest.raises(InputError) as e:
        thermokin.Robot.from_file(robot)
    assert str(robot) in str(e.value), str(e.value)
    with pytest.raises(ValueError):  # an InputError is a ValueError
        thermokin.Measurements.from_csv(bad, irb140)


def test_plan_is_a_subset_in_degrees(irb140):
    q = configurations(irb140, 300, 3)
    plan = thermokin.plan(irb140, q, poses=15, seed=1)
    assert plan.joints.shape == (15, 6)
    assert len(set(plan.indices)) == 15
    np.testing.assert_allclose(plan.joints, q[plan.indices], rtol=1e-14, atol=1e-12)
    assert plan.expected_xyz.shape == (15, 3)
    np.testing.assert_allclose(plan.expected_xyz[0], irb140.fk(plan.joints[0])[:3, 3], atol=1e-9)
    # The default criterion is the predicted error over the candidates: it never rises pose by pose.
    assert all(b <= a * (1 + 1e-9) for a, b in zip(plan.criterion_by_pose, plan.criterion_by_pose[1:]))
    assert plan.text.startswith("PLAN: 15 poses of 300 candidates")
    d_optimal = thermokin.plan(irb140, q, poses=15, seed=1, criterion="parameters")
    assert all(b >= a for a, b in zip(d_optimal.criterion_by_pose, d_optimal.criterion_by_pose[1:]))
    # Sampled candidates within a box of the base frame, and after measured poses.
    sampled = thermokin.plan(irb140, poses=5, samples=200, box=(-1000, -1000, 0, 1000, 1000, 1500))
    assert sampled.to_dict()["candidates"] == 200
    after = thermokin.plan(irb140, q, poses=5, measured=q[:20])
    assert after.to_dict()["measured"] == 20


def test_plan_for_the_poses_of_use(irb140):
    """`plan --for` from a notebook: the poses of use as degrees, the promise there against random draws,
    and an automatic count that says why it stopped."""
    q = configurations(irb140, 300, 3)
    plan = thermokin.plan(irb140, q, poses=20, region=q[:12], seed=1)
    promise = plan.to_dict()["promise"]
    assert promise["region"] == "given" and promise["poses_of_use"] == 12
    assert promise["planned_rms_mm"] < promise["random_rms_mm"]
    assert plan.to_dict()["criterion"] == "Prediction"
    auto = thermokin.plan(irb140, q, poses="auto", region=q[:12], seed=1)
    gain, resolution = auto.to_dict()["count"]["stopped"]
    assert gain < resolution
    with pytest.raises(InputError, match="auto"):
        thermokin.plan(irb140, q, poses="many")


def test_plan_for_poses_beyond_the_candidates_arcs(irb140):
    """Poses of use beyond the candidates' arcs: planned for at their nearest candidates by default, the
    promise stated there and beside it what the poses as given would be promised; `beyond_arcs="as-given"`
    plans for them as given."""
    q = configurations(irb140, 300, 3)
    q[:, 0] = np.clip(q[:, 0], -90.0, 90.0)
    use = q[:12].copy()
    use[:6, 0] = 120.0
    promise = thermokin.plan(irb140, q, poses=20, region=use, seed=1).to_dict()["promise"]
    assert promise["planned_at_nearest"] == 6
    assert promise["planned_as_given_rms_mm"] > 0.0
    given = thermokin.plan(irb140, q, poses=20, region=use, seed=1, beyond_arcs="as-given").to_dict()["promise"]
    assert given["planned_at_nearest"] == 0 and given["planned_as_given_rms_mm"] is None
    with pytest.raises(InputError, match="beyond_arcs"):
        thermokin.plan(irb140, q, poses=20, region=use, beyond_arcs="somewhere")


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"poses": 301}, "301 poses asked for, but only 300 candidates"),
        ({"criterion": "best"}, "criterion"),
        ({"effects": ["joint_offset:0"]}, "joints are numbered from 1"),
        ({"effects": ["thermal_drift:2"]}, "identified over operating time"),
    ],
)
def test_plan_bad_input(irb140, kwargs, message):
    with pytest.raises(InputError, match=message):
        thermokin.plan(irb140, configurations(irb140, 300, 3), **kwargs)


def test_a_backlash_follows_the_direction_given(root, tmp_path):
    # The IRB 140 with half a play of 0.02° in joint 3's gears: its side is the direction given.
    text = (root / "configs" / "irb140.toml").read_text()
    joints = text.split("[[joint]]")
    joints[3] = joints[3].rstrip("\n") + "\nbacklash = 0.02\n\n"
    path = tmp_path / "backlash.toml"
    path.write_text("[[joint]]".join(joints))
    robot = thermokin.Robot.from_file(path)
    plain = thermokin.Robot.from_file(root / "configs" / "irb140.toml")
    with pytest.raises(ThermokinError, match="direction"):
        robot.fk(Q)
    for side in (1, -1, 0):
        moved = list(Q)
        moved[2] += 0.02 * side
        T = robot.fk(Q, approach=[0, 0, side, 0, 0, 0])
        np.testing.assert_allclose(T, plain.fk(moved), rtol=0, atol=1e-9)
    with pytest.raises(ThermokinError, match=r"approach\[1\]"):
        robot.fk(Q, approach=[0, 2, 0, 0, 0, 0])
    # A batch takes one direction per row: each row on its own flank.
    rows = np.array([Q, Q, Q], dtype=float)
    sides = [[0, 0, s, 0, 0, 0] for s in (1, -1, 0)]
    moved = rows.copy()
    moved[:, 2] += 0.02 * np.array([1, -1, 0])
    np.testing.assert_allclose(robot.fk(rows, approach=sides), plain.fk(moved), rtol=0, atol=1e-9)
    # ik of those poses, each with its row's direction: the joints that reach them on that flank.
    solved = robot.ik(plain.fk(moved), seed=rows, approach=sides)
    assert list(solved.status) == ["Converged"] * 3
    np.testing.assert_allclose(robot.fk(solved.q, approach=sides), plain.fk(moved), rtol=0, atol=1e-6)
    with pytest.raises(ThermokinError, match="2 rows of directions for 3 rows"):
        robot.fk(rows, approach=sides[:2])


def test_lateral_joints_offers_a_bearings_tilt_without_masses(root, tmp_path):
    # The IRB 140 without masses, its base bearing tilting (simulated with lumped weights): named only
    # where the user says the joints are elastic.
    lines = (root / "configs" / "irb140.toml").read_text().splitlines()
    path = tmp_path / "massless.toml"
    path.write_text("\n".join(l for l in lines if not l.startswith(("mass_kg", "com_mm"))) + "\n")
    robot = thermokin.Robot.from_file(path)
    data = thermokin.simulate(robot, ["lateral_compliance:1"], poses=240, minutes=0)
    joints = thermokin.diagnose(robot, data, noise_mm=0.005, lateral="joints")
    assert "lateral_compliance[1] (no masses)" in joints.effects, joints.text
    by_default = thermokin.diagnose(robot, data, noise_mm=0.005)
    assert not any(e.startswith("lateral_compliance") for e in by_default.effects), by_default.text
    with pytest.raises(InputError, match="lateral"):
        thermokin.diagnose(robot, data, lateral="all")


def test_diagnose_predicts_its_error_at_the_poses_of_use(irb140):
    """`diagnose(..., region=)` as `diagnose --for`: the final model's predicted held-out error at the
    poses of use, with a hold-out set of those poses measured beside it."""
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05"], poses=120, minutes=0)
    held = thermokin.Measurements(irb140, data.q[80:], data.xyz[80:])
    report = thermokin.diagnose(irb140, data.q[:80], data.xyz[:80], holdout=held, region=data.q[80:], noise_mm=0.005)
    at_use = report.to_dict()["at_use"]
    assert at_use["poses"] == 40
    assert at_use["measured_rms_mm"] == pytest.approx(report.to_dict()["holdout"]["selected"]["heldout_rms_mm"])
    assert at_use["predicted_rms_mm"] > 0
    assert thermokin.diagnose(irb140, data.q[:80], data.xyz[:80]).to_dict()["at_use"] is None


def test_diagnose_restates_the_promise_of_the_plan_it_measured(irb140):
    """`diagnose(..., plan=)` as `diagnose --plan`: the plan's promise at its poses of use, restated at the
    residual scale the fit found (its figure at the plan's noise, scaled); a plan made for other poses of
    use is refused."""
    data = thermokin.simulate(irb140, ["joint_offset:2=0.05"], poses=120, minutes=0)
    use = data.q[80:]
    plan = thermokin.plan(irb140, data.q[:80], poses=30, region=use, noise_mm=0.005, seed=1)
    promise = plan.to_dict()["promise"]
    assert promise["poses_of_use"] == 40
    held = thermokin.Measurements(irb140, data.q[80:], data.xyz[80:])
    report = thermokin.diagnose(
        irb140, data.q[:80], data.xyz[:80], holdout=held, region=use, plan=plan, noise_mm=0.005
    )
    at_use = report.to_dict()["at_use"]
    scaled = promise["planned_rms_mm"] * at_use["residual_scale_mm"] / promise["noise_mm"]
    assert at_use["promised_rms_mm"] == pytest.approx(scaled, rel=1e-12)
    other = thermokin.plan(irb140, data.q[:80], poses=30, region=use[:12], noise_mm=0.005, seed=1)
    with pytest.raises(Exception, match="promised.poses"):
        thermokin.diagnose(irb140, data.q[:80], data.xyz[:80], region=use, plan=other, noise_mm=0.005)
