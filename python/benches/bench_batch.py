"""Batch FK of 1,000,000 configurations from numpy, beside Pinocchio's Python loop over the same
configurations in the same run (a ratio, on this processor), and IK of 10,000 targets.

    python python/benches/bench_batch.py [--configurations N] [--loop M]

Pinocchio's loop is timed on the first M configurations (default: all) and scaled per configuration;
both sides compute the tool frame's placement of the IRB 140 URDF. A benchmark, not a test: nothing
here asserts a speed.
"""

import argparse
import os
import pathlib
import platform
import time

import numpy as np

import thermokin

ROOT = pathlib.Path(__file__).resolve().parents[2]


def processor() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return f"{line.split(':', 1)[1].strip()}, {os.cpu_count()} cores"
    except OSError:
        pass
    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores"


def best_of(runs, f):
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--configurations", type=int, default=1_000_000)
    parser.add_argument("--loop", type=int, default=None, help="configurations for Pinocchio's loop")
    parser.add_argument("--ik-targets", type=int, default=10_000)
    args = parser.parse_args()

    urdf = ROOT / "fixtures" / "urdf" / "abb_irb140.urdf"
    robot = thermokin.Robot.from_file(urdf, tip="tool0")
    rng = np.random.default_rng(0)
    lim = robot.limits_deg
    q_deg = rng.uniform(lim[:, 0], lim[:, 1], size=(args.configurations, robot.dof))

    ours_s = best_of(3, lambda: robot.fk(q_deg))
    print(f"processor: {processor()}")
    print(f"thermokin batch FK, {args.configurations:,} configurations: {ours_s:.3f} s "
          f"({ours_s / args.configurations * 1e9:.0f} ns per configuration, numpy in and out)")

    try:
        import pinocchio as pin
    except ImportError:
        print("pinocchio not installed (pip install pin): no peer measured")
        pin = None
    if pin is not None:
        model = pin.buildModelFromUrdf(str(urdf))
        data = model.createData()
        frame = model.getFrameId("tool0", pin.BODY)
        m = args.loop or args.configurations
        q_rad = np.radians(q_deg[:m])
        idx = [model.joints[model.getJointId(n)].idx_q for n in robot.joint_names]
        qs = np.zeros((m, model.nq))
        qs[:, idx] = q_rad

        def loop():
            for q in qs:
                pin.forwardKinematics(model, data, q)
                pin.updateFramePlacement(model, data, frame)

        pin_s = best_of(1, loop) * args.configurations / m
        print(f"Pinocchio Python loop (forwardKinematics + updateFramePlacement), {m:,} configurations, "
              f"scaled to {args.configurations:,}: {pin_s:.3f} s ({pin_s / args.configurations * 1e9:.0f} ns each)")
        print(f"ratio thermokin / Pinocchio loop: {ours_s / pin_s:.4f} ({pin_s / ours_s:.0f}× faster)")
        # Same answers (the tests check this to 1e-9 mm; here a spot check).
        pin.forwardKinematics(model, data, qs[0])
        pin.updateFramePlacement(model, data, frame)
        assert np.allclose(robot.fk(q_deg[0])[:3, 3], data.oMf[frame].translation * 1000, atol=1e-9)

    targets = robot.fk(q_deg[: args.ik_targets])
    seed = np.zeros(robot.dof)
    ik_s = best_of(1, lambda: robot.ik(targets, seed=seed))
    result = robot.ik(targets, seed=seed)
    ok = int(np.sum(result.converged))
    print(f"thermokin batch IK, {args.ik_targets:,} random reachable poses from the zero seed: {ik_s:.3f} s "
          f"({ik_s / args.ik_targets * 1e6:.1f} µs each), {ok:,} converged (verified by FK)")


if __name__ == "__main__":
    main()
