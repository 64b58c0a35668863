"""What users run as written: the README's Python block, the worked example, and the stubs."""

import os
import re
import subprocess
import sys

import pytest


def python_section(root):
    text = (root / "README.md").read_text()
    start = text.index("## Python\n")
    end = text.index("\n## ", start + 1)
    return text[start:end]


def test_the_readme_commands_are_the_ci_commands(root):
    section = python_section(root)
    commands = re.findall(r"```sh\n(.*?)```", section, re.S)[0]
    lines = [l.split("#")[0].strip() for l in commands.strip().splitlines()]
    assert lines == [
        "cargo xtask wheel",
        'pip install "$(ls target/wheels/thermokin-*.whl)[test]"',
        "python -m pytest python/tests",
    ]
    ci = (root / ".ci" / "run").read_text()
    assert "cargo xtask wheel" in ci
    assert '"$venv/bin/pip" install "$(ls target/wheels/thermokin-*.whl)[test]"' in ci
    assert '"$venv/bin/python" -m pytest python/tests' in ci


def test_the_readme_python_block_runs_as_written(root, monkeypatch, capsys):
    block = re.findall(r"```python\n(.*?)```", python_section(root), re.S)
    assert len(block) == 1
    monkeypatch.chdir(root)
    exec(compile(block[0], "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "targets reached at minute 60" in out
    reached = int(out.strip().splitlines()[-1].split()[0])
    assert reached == 50, out


def test_the_worked_example_runs(root, tmp_path):
    env = dict(os.environ, MPLBACKEND="Agg")
    out = subprocess.run(
        [sys.executable, "python/examples/calibrate_ur10.py", str(tmp_path)],
        cwd=root, env=env, check=True, capture_output=True, text=True,
    ).stdout
    assert "program of 10 targets: 10 converged" in out, out
    for name in ["ur10-calibrated.toml", "ur10-calibrated.urdf", "program.csv"]:
        assert (tmp_path / name).stat().st_size > 0, name
    pytest.importorskip("matplotlib")
    assert (tmp_path / "residuals.png").stat().st_size > 0


def test_the_stub_matches_the_module():
    pytest.importorskip("mypy")
    run = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "thermokin._native"], capture_output=True, text=True
    )
    assert run.returncode == 0, run.stdout + run.stderr


def test_the_example_type_checks_against_the_stub(root):
    pytest.importorskip("mypy")
    run = subprocess.run(
        [sys.executable, "-m", "mypy", "--ignore-missing-imports", "python/examples/calibrate_ur10.py"],
        cwd=root, capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stdout + run.stderr
