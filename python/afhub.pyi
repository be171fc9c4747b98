"""Type hints of the native module afhub (python/src/*.cpp holds the docstrings)."""

import enum
from typing import Any, Callable, Dict, List, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

Vector = Union[Sequence[float], npt.NDArray[np.float64]]

class Error(RuntimeError): ...
class CommandRefused(Error): ...

class JointType(enum.Enum):
    EFFORT: int
    POSITION: int
    VELOCITY: int

JointTypes = Union[JointType, str, Sequence[Union[JointType, str]]]

def connect(wait_s: float = 0.0) -> None: ...
def catalog() -> List[Dict[str, Any]]: ...
def bodies() -> List[str]: ...
def resolve(name: str) -> str: ...
def loop_stats() -> List[Dict[str, Any]]: ...

class State:
    step: int
    time: float
    stamp_ns: int
    step_due_ns: int
    command_answered_step: int
    sequence: int
    publisher_pid: int
    position: npt.NDArray[np.float64]
    orientation: npt.NDArray[np.float64]
    linear_velocity: npt.NDArray[np.float64]
    angular_velocity: npt.NDArray[np.float64]
    force: npt.NDArray[np.float64]
    torque: npt.NDArray[np.float64]
    contact_force: npt.NDArray[np.float64]
    contact_torque: npt.NDArray[np.float64]
    contact_count: int
    mass: float
    inertia: npt.NDArray[np.float64]
    joint_count: int
    joint_positions: npt.NDArray[np.float64]
    joint_velocities: npt.NDArray[np.float64]
    joint_efforts: npt.NDArray[np.float64]
    sensor_distances: npt.NDArray[np.float64]
    sensor_ranges: npt.NDArray[np.float64]
    refused_commands: int
    refusal_reason: str

class Body:
    channel: str
    joint_names: List[str]
    sensor_rays: List[str]
    actuator_names: List[str]
    child_names: List[str]
    parent_name: str
    def __init__(self, name: str, wait_s: float = 0.0) -> None: ...
    def joint_index(self, name: str) -> int: ...
    def read(self, wait_s: float = 0.0) -> Optional[State]: ...
    def wait_next(self, after_step: Optional[int] = None, timeout_s: float = 5.0) -> State: ...
    def command(self, joint_values: Optional[Vector] = None,
                joint_types: Optional[JointTypes] = None, *,
                force: Optional[Vector] = None, torque: Optional[Vector] = None,
                position: Optional[Vector] = None, orientation: Optional[Vector] = None,
                linear_velocity: Optional[Vector] = None,
                angular_velocity: Optional[Vector] = None,
                actuators: Optional[Sequence[bool]] = None) -> None: ...
    def set_joint_positions(self, values: Vector) -> None: ...
    def set_joint_velocities(self, values: Vector) -> None: ...
    def set_joint_efforts(self, values: Vector) -> None: ...
    def check_refused(self) -> None: ...

class Device:
    channel: str
    def __init__(self, name: str, wait_s: float = 0.0) -> None: ...
    def read(self, wait_s: float = 0.0) -> Optional[Dict[str, Any]]: ...
    def command(self, *, force: Optional[Vector] = None, torque: Optional[Vector] = None,
                gripper_force: float = 0.0, enable: bool = True) -> None: ...

class World:
    def __init__(self, namespace: str = "") -> None: ...
    def state(self, wait_s: float = 2.0) -> Dict[str, Any]: ...
    def sim_step(self) -> int: ...
    def sim_time(self) -> float: ...
    def pause(self, timeout_s: float = 5.0) -> str: ...
    def resume(self, timeout_s: float = 5.0) -> str: ...
    def step(self, steps: int = 1, timeout_s: float = 5.0) -> str: ...
    def reset(self, timeout_s: float = 5.0) -> str: ...

class Loop:
    def __init__(self, rate_hz: float, callback: Callable[..., Optional[bool]], *,
                 body: Optional[Body] = None, lockstep: bool = False, name: str = "python",
                 fifo_priority: int = 0, cpu: int = -1, lock_memory: bool = False,
                 after_step_us: Optional[float] = None, unaligned: bool = False) -> None: ...
    def run(self, cycles: int = 0, seconds: float = 0.0) -> Dict[str, Any]: ...
    def stop(self) -> None: ...
