"""Type stubs of swarf's extension module (``swarf._swarf``). Use the ``swarf`` package's
functions; this module is what they call."""

from os import PathLike
from typing import Any, Callable, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, PathLike[str]]
_Arrays = Tuple[
    npt.NDArray[np.float64],  # xyz (N, 3)
    npt.NDArray[np.uint8],  # kind (N,)
    npt.NDArray[np.float64],  # feed (N,)
    npt.NDArray[np.int8],  # arc (N,)
    npt.NDArray[np.float64],  # center (N, 2)
    npt.NDArray[np.float64],  # start (3,)
    float,  # tool diameter
]

STRATEGIES: list[str]
POSTS: list[str]
OVERRIDES: list[str]
SETTINGS: list[str]
MOVE_KINDS: list[str]
EXAMPLE_CASE: str
DEFAULT_STEPDOWN_FRACTION: float
VERSION: str

class SwarfError(Exception):
    """Every error swarf raises about what it was given."""

class InputError(SwarfError):
    """A bad input file."""

    file: str
    place: str
    reason: str

class SettingError(SwarfError):
    """An option out of its range."""

    setting: str
    reason: str

class JobError(SwarfError):
    """A job that cannot be machined as asked."""

    place: str
    reason: str

class RefusedError(SwarfError):
    """An output refused before anything is written."""

    file: str
    reason: str

class OutputError(SwarfError):
    """An output that cannot be made."""

    what: str
    reason: str

class Job:
    """A job read from a file or from Python data, with the overrides it was read with."""

    @property
    def kind(self) -> str:
        """``"2.5d"`` or ``"3d"``."""
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> str: ...
    @property
    def tool_diameter(self) -> float: ...
    @property
    def engagement_deg(self) -> float: ...
    @property
    def summary(self) -> str: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def files(self) -> list[str]: ...
    def with_overrides(self, **overrides: Any) -> Job: ...
    @staticmethod
    def from_dict(case: Any, name: str = "job", base_dir: Optional[_Path] = None, **overrides: Any) -> Job:
        """A job from a case given as Python data (lists or NumPy arrays of points)."""
    @staticmethod
    def from_mesh(vertices: Any, triangles: Any, name: str = "part", **overrides: Any) -> Job:
        """A 3D job from a mesh: vertices (n, 3) and triangles (m, 3) of vertex indices."""

class RoughOutput:
    @property
    def gcode(self) -> str: ...
    @property
    def report_json(self) -> str: ...
    def moves(self) -> _Arrays: ...
    def samples(self) -> Optional[npt.NDArray[np.float64]]: ...
    def write(self, path: _Path, report: Optional[_Path] = None) -> None: ...

def load(path: _Path, **overrides: Any) -> Job: ...
def load_case_text(text: str, path: _Path, **overrides: Any) -> Job: ...
def rough(job: Job, progress: Optional[Callable[[str, float], Any]] = None, **settings: Any) -> RoughOutput: ...
def check(
    job: Job, gcode: str, name: str = "program.ngc", tool_diameter: Optional[float] = None, **settings: Any
) -> str: ...
def plan_tools(
    job: Job, tools: _Path, tools_text: Optional[str] = None, **settings: Any
) -> Tuple[list[Tuple[str, str, _Arrays]], str]: ...
def write_files(files: Sequence[Tuple[_Path, bytes]], inputs: Sequence[_Path] = ...) -> None: ...
