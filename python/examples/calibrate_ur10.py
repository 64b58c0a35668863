"""Calibrate a real UR10 from laser-tracker data, then compensate with what was found.

Series C (fitted) and series B (held out, other configurations) of the UR10 in
``fixtures/real/ur10-ipa/``: diagnose C, score on B, plot the residuals before and after (when
matplotlib is installed), export the calibrated robot, and compute the joints that put the calibrated
robot on B's measured points.

    python python/examples/calibrate_ur10.py [OUTPUT_DIR]

Run from the repository root (the data paths are relative to it).
"""

import pathlib
import sys

import numpy as np

import thermokin


def main(out: pathlib.Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    data = pathlib.Path("fixtures/real/ur10-ipa")
    robot = thermokin.Robot.from_file("fixtures/urdf/ur10.urdf", tip="tool0")
    fit = thermokin.Measurements.from_csv(data / "series_C.csv", robot)
    held = thermokin.Measurements.from_csv(data / "series_B.csv", robot)
    print(f"{robot}: {len(fit)} poses to fit, {len(held)} held out")

    # The tracker's frame and the probe's offset are unknown: both are estimated with the effects.
    report = thermokin.diagnose(robot, fit, holdout=held, noise_mm=0.01, frame="tracker", tool="unknown")
    print(report.text)
    holdout = report.to_dict()["holdout"]
    print(
        f"held-out series B: nominal mean {holdout['nominal']['heldout_mean_mm']:.3f} mm → "
        f"calibrated {holdout['selected']['heldout_mean_mm']:.3f} mm"
    )

    residuals = report.residuals()
    try:
        import matplotlib.pyplot as plt
    except ImportError:
        print("(matplotlib not installed: no plot)")
    else:
        fig, ax = plt.subplots(figsize=(9, 4))
        ax.plot(residuals["before"], ".", label="nominal model")
        ax.plot(residuals["after"], ".", label="with the effects found")
        ax.set_xlabel("measurement (series C)")
        ax.set_ylabel("|residual| [mm]")
        ax.legend()
        fig.savefig(out / "residuals.png", dpi=100)
        print(f"plot: {out / 'residuals.png'}")

    # The model the report scored, written for ROS / RoboDK (URDF) and complete (TOML).
    report.export(out / "ur10-calibrated.toml")
    calibrated = report.calibrated
    calibrated.save(out / "ur10-calibrated.urdf")
    print(f"exported: {out / 'ur10-calibrated.toml'}, {out / 'ur10-calibrated.urdf'}")

    # The joints that put the calibrated robot on B's measured points (tracker frame), each solved from
    # the joints B commanded, the tool's orientation as the calibrated model has it there: how far the
    # calibration moves a commanded pose.
    q_b = held.q
    poses = calibrated.fk(q_b)
    poses[:, :3, 3] = held.xyz
    solved = calibrated.ik(poses, seed=q_b)
    ok = np.asarray(solved.converged)
    print(
        f"B's {len(held)} measured points on the calibrated robot: {ok.sum()} reached; joints move by "
        f"{np.abs(solved.q[ok] - q_b[ok]).max(axis=1).mean():.4f}° on average (largest joint per pose)"
    )

    # Compensation of a program: ten targets 10 mm apart, from a pose of B away from the stretched-arm
    # singularity (elbow and wrist bent), chained as a robot runs them, on the calibrated robot.
    bent = int(np.argmax((np.abs(q_b[:, 2]) > 30) & (np.abs(q_b[:, 4]) > 20)))
    start = thermokin.pose_to_xyz_euler(poses[bent])
    targets = np.array([start + [0, 0, 10.0 * k, 0, 0, 0] for k in range(10)])
    run = thermokin.compensate(calibrated, targets, seed=q_b[bent])
    reached = calibrated.fk(run.joints)[:, :3, 3]
    print(f"program of {len(run)} targets: {run.status.count('Converged')} converged")
    print(f"largest |FK(joints) − target| on the calibrated robot: {np.abs(reached - targets[:, :3]).max():.2e} mm")
    run.write(out / "program.csv", format="joints")
    print(f"joints: {out / 'program.csv'}")

if __name__ == "__main__":
    main(pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "target/calibrate_ur10"))
