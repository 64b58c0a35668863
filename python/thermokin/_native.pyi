"""Types of the native module (checked against it by ``mypy.stubtest`` in the tests)."""

import os
from typing import Any, Sequence, Union, final

import numpy as np
import numpy.typing as npt

__all__ = [
    "Compensation",
    "IKResult",
    "Measurements",
    "Plan",
    "Report",
    "Robot",
    "compensate",
    "diagnose",
    "plan",
    "pose_to_xyz_euler",
    "simulate",
]

_Path = Union[str, "os.PathLike[str]"]
_Array = npt.ArrayLike
_F64 = npt.NDArray[np.float64]

@final
class Robot:
    """A robot: its kinematic chain and what a calibration added. Millimetres and degrees."""

    @staticmethod
    def from_file(path: _Path, *, tip: str | None = None, base: str | None = None) -> Robot: ...
    @staticmethod
    def from_dh(
        rows: _Array,
        *,
        convention: str = "classic",
        names: Sequence[str] | None = None,
        base: _Array | None = None,
        tool: _Array | None = None,
        name: str = "dh",
    ) -> Robot: ...
    @property
    def name(self) -> str: ...
    @property
    def dof(self) -> int: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def branches(self) -> dict[str, tuple[int, list[str]]]: ...
    @property
    def limits_deg(self) -> _F64: ...
    @property
    def is_plain(self) -> bool: ...
    @property
    def beyond_urdf(self) -> list[str]: ...
    def fk(
        self,
        q: _Array,
        *,
        time_min: float | None = None,
        temps: dict[str, float] | None = None,
        approach: list[int] | list[list[int]] | None = None,
    ) -> _F64: ...
    def jacobian(
        self,
        q: _Array,
        *,
        time_min: float | None = None,
        temps: dict[str, float] | None = None,
        approach: list[int] | list[list[int]] | None = None,
    ) -> _F64: ...
    def ik(
        self,
        pose: _Array,
        seed: _Array | None = None,
        *,
        position_only: bool = False,
        time_min: float | None = None,
        temps: dict[str, float] | None = None,
        approach: list[int] | list[list[int]] | None = None,
        restarts: int | None = None,
    ) -> IKResult: ...
    def deformed(
        self,
        deformation: _Path,
        *,
        semantics: str | None = None,
        profile: str | None = None,
        time_min: float | None = None,
    ) -> Robot: ...
    def to_urdf(self) -> str: ...
    def to_toml(self) -> str: ...
    def save(self, path: _Path) -> None: ...

@final
class IKResult:
    """Inverse kinematics of one target (scalars) or a batch (arrays and a list of statuses)."""

    @property
    def q(self) -> _F64: ...
    @property
    def status(self) -> str | list[str]: ...
    @property
    def position_error_mm(self) -> float | _F64: ...
    @property
    def orientation_error_deg(self) -> float | _F64: ...
    @property
    def iterations(self) -> int | npt.NDArray[np.uint64]: ...
    @property
    def converged(self) -> bool | npt.NDArray[np.bool_]: ...

@final
class Measurements:
    """Joint values, measured tool positions, times and sensor readings."""

    def __new__(
        cls,
        robot: Robot,
        q: _Array,
        xyz: _Array,
        *,
        time_min: _Array | None = None,
        temps: dict[str, _Array] | None = None,
        joint_units: str | None = None,
        position_units: str | None = None,
    ) -> Measurements: ...
    @staticmethod
    def from_csv(
        path: _Path, robot: Robot, *, joint_units: str | None = None, position_units: str | None = None
    ) -> Measurements: ...
    def to_csv(self, path: _Path) -> None: ...
    def __len__(self) -> int: ...
    @property
    def q(self) -> _F64: ...
    @property
    def xyz(self) -> _F64: ...
    @property
    def time_min(self) -> _F64: ...
    @property
    def temperature_names(self) -> list[str]: ...

@final
class Report:
    """What `diagnose` found."""

    @property
    def text(self) -> str: ...
    def to_json(self) -> str: ...
    def to_dict(self) -> dict[str, Any]: ...
    def html(self) -> str: ...
    @property
    def effects(self) -> list[str]: ...
    @property
    def completed(self) -> list[str]: ...
    @property
    def shrinkage(self) -> float: ...
    @property
    def verdict(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def honest_end(self) -> str | None: ...
    @property
    def calibrated(self) -> Robot: ...
    def export(self, path: _Path, *, force: bool = False) -> None: ...
    def residuals(self) -> dict[str, _F64]: ...
    def to_dataframe(self) -> Any: ...

@final
class Plan:
    """A measurement plan: the poses in measuring order and what they are predicted to give."""

    @property
    def text(self) -> str: ...
    @property
    def joints(self) -> _F64: ...
    @property
    def indices(self) -> list[int]: ...
    @property
    def expected_xyz(self) -> _F64: ...
    @property
    def criterion_by_pose(self) -> list[float]: ...
    def to_dict(self) -> dict[str, Any]: ...
    def html(self) -> str: ...

@final
class Compensation:
    """Per target (and time): the joints to command and how the robot reaches the target with them."""

    @property
    def labels(self) -> list[str]: ...
    @property
    def time_min(self) -> _F64: ...
    @property
    def joints(self) -> _F64: ...
    @property
    def status(self) -> list[str]: ...
    @property
    def position_error_mm(self) -> _F64: ...
    @property
    def orientation_error_deg(self) -> _F64: ...
    @property
    def uncompensated_error_mm(self) -> _F64: ...
    def summary(self) -> dict[str, Any]: ...
    def write(self, path: _Path, *, format: str | None = None) -> None: ...
    def to_dataframe(self) -> Any: ...
    def __len__(self) -> int: ...

def simulate(
    robot: Robot,
    effects: Sequence[str] | None = None,
    *,
    poses: int | None = None,
    minutes: float | None = None,
    noise_mm: float | None = None,
    orientation_noise_deg: float | None = None,
    seed: int | None = None,
) -> Measurements: ...
def diagnose(
    robot: Robot,
    data: Measurements | _Array,
    xyz: _Array | None = None,
    *,
    time_min: _Array | None = None,
    temps: dict[str, _Array] | None = None,
    holdout: Measurements | None = None,
    noise_mm: float | None = None,
    folds: int | None = None,
    folds_by: str | None = None,
    frame: str | None = None,
    tool: str | None = None,
    orientation_lever_mm: float | None = None,
    orientation_noise_deg: float | None = None,
    outliers: str | None = None,
    shrinkage: str | None = None,
    extrapolation: str | None = None,
    masses: str | None = None,
    order: str | None = None,
    lateral: str | None = None,
    accelerometers: dict[str, int] | None = None,
    region: _Array | None = None,
    plan: Plan | None = None,
) -> Report: ...
def plan(
    robot: Robot,
    candidates: _Array | None = None,
    *,
    poses: int | str | None = None,
    measured: _Array | None = None,
    samples: int | None = None,
    box: Sequence[float] | None = None,
    effects: Sequence[str] | None = None,
    noise_mm: float | None = None,
    criterion: str | None = None,
    frame: str | None = None,
    tool: str | None = None,
    seed: int | None = None,
    region: _Array | None = None,
    beyond_arcs: str | None = None,
) -> Plan: ...
def compensate(
    robot: Robot,
    targets: _Path | _Array,
    *,
    deformation: _Path | None = None,
    semantics: str | None = None,
    profile: str | None = None,
    time_min: float | None = None,
    temps: dict[str, float] | None = None,
    duration_min: float | None = None,
    step_min: float | None = None,
    seed: _Array | None = None,
    accumulate: str | None = None,
) -> Compensation: ...
def pose_to_xyz_euler(pose: _Array) -> _F64: ...
