"""Shared fixtures: the repository root (fixtures, configs) and the command line built by cargo."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def root() -> pathlib.Path:
    return ROOT


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The `thermokin` binary — the independent front end the Python results are compared with: the one
    `THERMOKIN_CLI` names (a wheel's tests run where no Rust toolchain is), else built (release) by cargo
    in the workspace's target directory."""
    given = os.environ.get("THERMOKIN_CLI")
    if given:
        exe = pathlib.Path(given).resolve()
        assert exe.exists(), exe
        return exe
    subprocess.run(
        ["cargo", "build", "--release", "--locked", "--quiet", "-p", "thermokin"], cwd=ROOT, check=True
    )
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    if not target.is_absolute():
        target = ROOT / target
    exe = target / "release" / "thermokin"
    assert exe.exists(), exe
    return exe
