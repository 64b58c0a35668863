"""Parity of the two front ends: the same inputs through the command line (its JSON) and through Python,
compared field by field — fk and ik (a plain robot and a calibrated, drifting one at a time), compensate
(a static table and a calibrated robot at a time), diagnose (its defaults, and every setting given) — so
that neither front end decides anything the other does not."""

import json
import subprocess

import numpy as np
import pytest

import thermokin

Q = [[0, 30, 10, 0, -40, 0], [20, -10, 35, 45, 60, -90], [-60, 45, -20, 120, -30, 10]]


def pose_xyz_euler(x, y, z, a, b, c):
    """The 4×4 pose of a position (mm) and X-Y-Z Euler angles (degrees, R = Rx·Ry·Rz), built here."""
    a, b, c = np.radians([a, b, c])
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
    rz = np.array([[np.cos(c), -np.sin(c), 0], [np.sin(c), np.cos(c), 0], [0, 0, 1]])
    t = np.eye(4)
    t[:3, :3] = rx @ ry @ rz
    t[:3, 3] = [x, y, z]
    return t


def run(cli, root, *args):
    out = subprocess.run([cli, *map(str, args)], cwd=root, capture_output=True, text=True)
    assert out.returncode in (0, 3), out.stderr
    return out.stdout


@pytest.fixture(scope="module")
def warm(root, cli, tmp_path_factory):
    """A calibrated robot that drifts with time: a simulated warm-up diagnosed by the command line."""
    d = tmp_path_factory.mktemp("warm")
    m, robot = d / "m.csv", d / "warm.toml"
    run(cli, root, "simulate", "--robot", "configs/irb140.toml", "--effect", "joint_offset:2", "--effect",
        "thermal_drift:3", "--minutes", "180", "--poses", "120", "-o", m)
    run(cli, root, "diagnose", "--robot", "configs/irb140.toml", "--measurements", m, "--quiet",
        "--force-export", "--export", robot)
    return robot


@pytest.mark.parametrize("calibrated,time_min", [(False, None), (True, 0.0), (True, 90.0)])
def test_fk_field_by_field(root, cli, warm, calibrated, time_min):
    for path in [str(warm) if calibrated else "configs/irb140.toml"]:
        robot = thermokin.Robot.from_file(root / path)
        for q in Q:
            args = ["fk", "--robot", path, "--joints", ",".join(map(str, q)), "--json"]
            if time_min is not None:
                args += ["--time", time_min]
            theirs = json.loads(run(cli, root, *args))
            ours = robot.fk(q, time_min=time_min) if time_min is not None else robot.fk(q)
            np.testing.assert_allclose(ours[:3, 3], theirs["position_mm"], atol=1e-9)
            np.testing.assert_allclose(ours[:3, :3], theirs["rotation"], atol=1e-12)


def test_ik_field_by_field(root, cli, warm):
    for path, time_min in [("configs/irb140.toml", None), (str(warm), 60.0)]:
        robot = thermokin.Robot.from_file(root / path)
        seed = [0, 20, 20, 0, -45, 0]
        for pose in ["600,0,400,0,90,0", "500,100,500,0,90,0"]:
            args = ["ik", "--robot", path, "--pose", pose, "--seed", ",".join(map(str, seed)), "--json"]
            kw = {}
            if time_min is not None:
                args += ["--time", time_min]
                kw["time_min"] = time_min
            theirs = json.loads(run(cli, root, *args))
            x, y, z, a, b, c = map(float, pose.split(","))
            target = pose_xyz_euler(x, y, z, a, b, c)
            ours = robot.ik(target, seed, **kw)
            assert ours.status == theirs["status"]
            np.testing.assert_allclose(ours.q, theirs["joints_deg"], atol=1e-9)
            np.testing.assert_allclose(ours.position_error_mm, theirs["position_error_mm"], atol=1e-12)


def test_compensate_field_by_field(root, cli, warm, tmp_path):
    cases = [
        ("configs/irb140.toml", ["--deformation", "fixtures/paper/deformations-case-study.toml"],
         {"deformation": root / "fixtures/paper/deformations-case-study.toml"}),
        (str(warm), ["--time", "60"], {"time_min": 60.0}),
    ]
    for path, flags, kw in cases:
        out = tmp_path / "r.json"
        run(cli, root, "compensate", "--robot", path, "--targets", "fixtures/paper/table12-targets.csv",
            "--seed", "0,20,20,0,-45,0", "--format", "json", "--out", out, *flags)
        theirs = json.loads(out.read_text())
        robot = thermokin.Robot.from_file(root / path)
        ours = thermokin.compensate(robot, str(root / "fixtures/paper/table12-targets.csv"),
                                    seed=[0, 20, 20, 0, -45, 0], **kw)
        assert len(ours) == len(theirs["rows"])
        assert ours.status == [r["status"] for r in theirs["rows"]]
        np.testing.assert_allclose(ours.joints, [r["joints_deg"] for r in theirs["rows"]], atol=1e-9)
        assert ours.summary()["failures"] == theirs["summary"]["failures"]


@pytest.mark.parametrize(
    "flags,kw",
    [
        ([], {}),
        (["--frame", "tracker", "--tool", "unknown", "--folds", "4", "--folds-by", "time", "--noise", "0.005",
          "--outliers", "keep", "--shrinkage", "off", "--extrapolation", "off"],
         {"frame": "tracker", "tool": "unknown", "folds": 4, "folds_by": "time", "noise_mm": 0.005,
          "outliers": "keep", "shrinkage": "off", "extrapolation": "off"}),
        (["--masses", "ignore", "--noise", "0.005"], {"masses": "ignore", "noise_mm": 0.005}),
    ],
)
def test_diagnose_field_by_field(root, cli, tmp_path, flags, kw):
    m, out = tmp_path / "m.csv", tmp_path / "r.json"
    run(cli, root, "simulate", "--robot", "configs/irb140.toml", "--effect", "joint_offset:2", "--effect",
        "tool_frame", "--poses", "80", "--minutes", "0", "-o", m)
    run(cli, root, "diagnose", "--robot", "configs/irb140.toml", "--measurements", m, "--quiet",
        "--json", out, *flags)
    theirs = json.loads(out.read_text())
    robot = thermokin.Robot.from_file(root / "configs/irb140.toml")
    ours = thermokin.diagnose(robot, thermokin.Measurements.from_csv(m, robot), **kw).to_dict()
    assert ours == theirs


def test_plan_field_by_field(root, cli, tmp_path):
    """`thermokin plan` and `thermokin.plan` on the same candidates: the same poses in the same order, the
    same predictions."""
    candidates = root / "fixtures" / "real" / "jacobi-wam" / "wam-grid.csv"
    out, report = tmp_path / "plan.csv", tmp_path / "plan.json"
    run(cli, root, "plan", "--robot", "fixtures/real/jacobi-wam/wam.urdf", "--candidates", candidates,
        "--frame", "tracker", "--tool", "unknown", "--poses", 20, "--out", out, "--json", report)
    theirs = json.loads(report.read_text())
    robot = thermokin.Robot.from_file(root / "fixtures" / "real" / "jacobi-wam" / "wam.urdf")
    q = np.loadtxt(candidates, delimiter=",", skiprows=1, usecols=range(7))
    ours = thermokin.plan(robot, q, poses=20, frame="tracker", tool="unknown")
    assert ours.indices == [p["candidate"] for p in theirs["poses"]]
    np.testing.assert_allclose(ours.joints, [p["joints"] for p in theirs["poses"]], atol=1e-9)
    mine = ours.to_dict()
    assert mine["comparison"]["planned_criterion"] == pytest.approx(theirs["comparison"]["planned_criterion"], rel=1e-12)
    assert [p["parameter"] for p in mine["parameters"]] == [p["parameter"] for p in theirs["parameters"]]
    # The CLI's CSV: the candidates' file lines (header = line 1) and values.
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows[:, 1] - 2, ours.indices)
    np.testing.assert_allclose(rows[:, 2:9], ours.joints, atol=1e-9)
