"""Type stubs of the package structomat (see its docstrings)."""

import os
from typing import Any, Dict, List, Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

Column = Union[npt.NDArray[np.float64], List[str]]

class Error(RuntimeError):
    """An error of structomat, with host-sim's (or the core's) message."""
    result: "Result"

class TwinError(Error):
    """A step of Twin refused or failed; the twin keeps its last good state."""

class Result:
    columns: Dict[str, Column]
    events: Dict[str, Column]
    switches: Dict[str, Column]
    summary: Dict[str, Any]
    def __init__(self, columns: Dict[str, Column], events: Dict[str, Column],
                 switches: Dict[str, Column], summary: Dict[str, Any]) -> None: ...
    def __len__(self) -> int: ...

def run(
    source: Union[str, "os.PathLike[str]"],
    *,
    h: Optional[float] = ...,
    step: Optional[float] = ...,
    t_end: Optional[float] = ...,
    every: Optional[int] = ...,
    f32: bool = ...,
    f64: bool = ...,
    motor: Optional[float] = ...,
    load: Optional[float] = ...,
    ccw: bool = ...,
    spread_events: bool = ...,
) -> Result: ...

def scenarios() -> List[Tuple[str, str]]: ...

def sweep(
    path: Union[str, "os.PathLike[str]"],
    out_dir: Union[str, "os.PathLike[str]"],
    client: Any = None,
    batch: Optional[int] = None,
) -> Dict[str, Any]: ...

class Twin:
    def __init__(
        self,
        source: str = "ccc-s2",
        *,
        h: Optional[float] = ...,
        step: Optional[float] = ...,
        f32: bool = ...,
        f64: bool = ...,
        motor: Optional[float] = ...,
        load: Optional[float] = ...,
        ccw: bool = ...,
        spread_events: bool = ...,
    ) -> None: ...
    def step(
        self,
        motor: Optional[float] = None,
        load: Optional[float] = None,
        measured: Optional[Tuple[int, int, float]] = None,
    ) -> None: ...
    def state(self) -> Dict[str, Union[float, str]]: ...
    @property
    def steps(self) -> int: ...
    @property
    def time(self) -> float: ...
    @property
    def lag(self) -> float: ...
    @property
    def h(self) -> float: ...
    @property
    def precision(self) -> str: ...
    @property
    def mode(self) -> str: ...
    @property
    def mode_code(self) -> int: ...
    @property
    def coordinates(self) -> str: ...
    @property
    def q(self) -> npt.NDArray[np.float64]: ...
    @property
    def qd(self) -> npt.NDArray[np.float64]: ...
    @property
    def theta(self) -> npt.NDArray[np.float64]: ...
    @property
    def omega(self) -> npt.NDArray[np.float64]: ...
    @property
    def crank_angle(self) -> float: ...
    @property
    def crank_speed(self) -> float: ...
    @property
    def shaft_angle(self) -> float: ...
    @property
    def shaft_speed(self) -> float: ...
    @property
    def c6(self) -> float: ...
    @property
    def c8(self) -> float: ...
    @property
    def motor_torque(self) -> float: ...
    @property
    def audit(self) -> Dict[str, float]: ...
    @property
    def measurement_residual(self) -> Optional[float]: ...
    @property
    def events(self) -> List[Dict[str, Union[float, str]]]: ...
    @property
    def switches(self) -> List[Dict[str, Union[float, str]]]: ...
def design(
    path: Union[str, "os.PathLike[str]"],
    client: Any = None,
) -> Dict[str, Any]: ...
