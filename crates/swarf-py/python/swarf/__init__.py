"""swarf: CNC roughing toolpaths a machinist can trust, from Python.

A thin face over the swarf library (written in Rust): the same jobs, options, defaults, checks,
programs and figures as the ``swarf`` command, with the GIL released while swarf works.

    >>> import swarf
    >>> job = swarf.load("examples/cases/pocket_islands.json")
    >>> res = swarf.rough(job, strategy="adaptive", tool_diameter=6)
    >>> res.report["time_min"], res.report["engagement_deg"]["max"]
    >>> res.toolpath.xyz.shape          # (moves, 3) float64
    >>> res.engagement[:, ENGAGEMENT_COLUMNS.index("tea_deg")]
    >>> res.write("pocket_islands.ngc", report="pocket_islands.json")

Jobs come from files (``load``: cases, STL parts, DXF and SVG drawings) or from Python data
(``Job.from_dict``: a case as a dict, point lists as lists or NumPy arrays). ``rough`` plans,
posts and proves a program; ``plan_tools`` finds the cheapest tool sequence for a 3D job;
``check`` proves any program's G-code on a job. ``swarf.batch`` runs many jobs on a Dask
cluster (``swarf.cluster``). Errors are ``SwarfError`` subclasses carrying the file, the place and the reason.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Callable, Iterable, Mapping, Optional, Sequence, Union

from . import _swarf
from ._swarf import (
    InputError,
    JobError,
    OutputError,
    RefusedError,
    SettingError,
    SwarfError,
)

__version__: str = _swarf.VERSION

#: The clearing strategies' names.
STRATEGIES: Sequence[str] = tuple(_swarf.STRATEGIES)
#: The controller dialects' names.
POSTS: Sequence[str] = tuple(_swarf.POSTS)
#: Keywords that override what the job's file says (read again with them).
OVERRIDES: Sequence[str] = tuple(_swarf.OVERRIDES)
#: Keywords that set the run (strategy, post, links, simulation).
SETTINGS: Sequence[str] = tuple(_swarf.SETTINGS)
#: The columns of ``RoughResult.engagement`` (as the command line's ``--samples`` CSV).
ENGAGEMENT_COLUMNS: Sequence[str] = (
    "cut_length_mm",
    "x",
    "y",
    "z",
    "tea_deg",
    "tea_pixel_deg",
    "kind",
    "bore",
    "move",
)
#: The sample kinds in ``engagement[:, 6]``.
SAMPLE_KINDS: Sequence[str] = ("lateral", "descending", "plunge")
#: The move kinds in ``Toolpath.kind``.
MOVE_KINDS: Sequence[str] = tuple(_swarf.MOVE_KINDS)

PathLike = Union[str, "os.PathLike[str]"]
Progress = Callable[[str, float], Any]

Job = _swarf.Job

__all__ = [
    "Job",
    "load",
    "example",
    "rough",
    "check",
    "plan_tools",
    "RoughResult",
    "ToolPlan",
    "Toolpath",
    "SwarfError",
    "InputError",
    "SettingError",
    "JobError",
    "RefusedError",
    "OutputError",
    "STRATEGIES",
    "POSTS",
    "OVERRIDES",
    "SETTINGS",
    "ENGAGEMENT_COLUMNS",
    "SAMPLE_KINDS",
    "MOVE_KINDS",
]


def load(path: PathLike, **overrides: Any) -> Job:
    """Reads a job from a file: a case (``.json``, 2.5D or 3D), an STL part, or a DXF or SVG
    drawing.

    Keywords override what the file says, named as the command line's flags:
    ``tool_diameter``, ``engagement`` (degrees) or ``stepover`` (a fraction of the diameter),
    ``stepdown``, ``depth`` (drawings), ``feed``, ``max_feed``, ``spindle``, ``allowance``,
    ``units`` (``"mm"``, ``"in"``, ``"cm"``, ``"m"``), ``svg_dpi``, ``chain_tolerance``,
    ``cut``, ``skip_open``, ``layers``, ``ignore_layers``, ``part_rotate``,
    ``part_translate``, ``part_scale``, ``stock_margin``, ``stock_above``.

    Raises ``InputError`` (a bad file: ``.file``, ``.place``, ``.reason``), ``SettingError``
    (a bad override: ``.setting``, ``.reason``), ``OSError`` (an unreadable file).
    """
    return _swarf.load(os.fspath(path), **overrides)


def example(**overrides: Any) -> Job:
    """The built-in example job, as ``swarf demo`` roughs it: a 90 × 60 mm pocket with two
    islands, a Ø6 mm end mill at 25 % stepover, two levels (no file needed). Keywords override
    it as in ``load``."""
    return _swarf.load_case_text(_swarf.EXAMPLE_CASE, "demo_pocket.json", **overrides)


def _plain(value: Any) -> Any:
    """JSON-ready data from NumPy arrays and scalars (anything with ``tolist``)."""
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"not JSON data: {type(value).__name__}")


class Toolpath:
    """A program's moves as NumPy arrays, one row per move.

    - ``xyz``: (N, 3) float64, where each move ends, mm;
    - ``kind``: (N,) uint8, an index into ``MOVE_KINDS`` (0 is a rapid);
    - ``feed``: (N,) float64, mm/min (0 for rapids);
    - ``arc``: (N,) int8, 0 for a straight move, 1 counter-clockwise, -1 clockwise (G17);
    - ``center``: (N, 2) float64, an arc's centre (NaN for straight moves);
    - ``start``: (3,) float64, where the tool is before the first move;
    - ``tool_diameter``: mm.

    ``numpy.asarray(toolpath)`` is ``xyz``.
    """

    __slots__ = ("xyz", "kind", "feed", "arc", "center", "start", "tool_diameter")

    def __init__(self, arrays: tuple) -> None:
        (self.xyz, self.kind, self.feed, self.arc, self.center, self.start, self.tool_diameter) = arrays

    def __len__(self) -> int:
        return len(self.xyz)

    def __array__(self, dtype=None, copy=None):
        return self.xyz if dtype is None else self.xyz.astype(dtype)

    def __repr__(self) -> str:
        return f"<swarf.Toolpath {len(self)} moves, tool Ø{self.tool_diameter} mm>"


class RoughResult:
    """What ``rough`` made: ``gcode`` (str), ``report`` (dict, as the command line's
    ``--report`` JSON), ``toolpath`` (``Toolpath``), ``engagement`` ((M, 9) float64, the
    simulation's samples, columns ``ENGAGEMENT_COLUMNS``; None when not simulated)."""

    def __init__(self, out: Any) -> None:
        self._out = out
        self.gcode: str = out.gcode
        self.report: dict = json.loads(out.report_json)
        self._toolpath: Optional[Toolpath] = None
        self._engagement: Any = None

    @property
    def toolpath(self) -> Toolpath:
        if self._toolpath is None:
            self._toolpath = Toolpath(self._out.moves())
        return self._toolpath

    @property
    def engagement(self) -> Any:
        if self._engagement is None:
            self._engagement = self._out.samples()
        return self._engagement

    def write(self, path: PathLike, report: Optional[PathLike] = None) -> None:
        """Writes the G-code (and the report as JSON) atomically: each file appears whole or
        not at all, and none may replace one of the job's input files (``RefusedError``)."""
        self._out.write(os.fspath(path), None if report is None else os.fspath(report))

    def __repr__(self) -> str:
        r = self.report
        return f"<swarf.RoughResult {r.get('strategy')} {r.get('time_min', 0):.2f} min, {r.get('gcode_lines')} lines>"


def rough(job: Job, progress: Optional[Progress] = None, **settings: Any) -> RoughResult:
    """Roughs a job: plans the program, posts it and proves it on the simulator (unless
    ``simulate=False``), as ``swarf rough`` does; the GIL is released meanwhile.

    Keywords are the run's settings, named as the command line's flags: ``strategy`` (one of
    ``STRATEGIES``, adaptive by default), ``post`` (``POSTS``), ``conventional``, ``order``,
    ``angle``, ``stock_to_leave``, ``finish``, ``ramp_angle``, ``overshoot``, ``feed_boost``,
    ``feed_links``, ``level_by_level``, ``full_circles``, ``zeta``, ``spiral_start`` ((x, y)),
    ``spiral_floor``, ``optimise``, ``arc_tolerance``, ``clearance``, ``res``, ``sim``
    (``"raster"``, ``"sdf"``), ``simulate``, ``exact_every_sample``; and any of the job's
    overrides (``tool_diameter=…``, ``engagement=…``, … as in ``load``), with which the job is
    read again. A 3D job is roughed in z-levels.

    ``progress(stage, fraction)`` is called with ``"plan"`` or ``"simulate"`` and the share
    of it done, at most every 1 %; an exception it raises is raised when the run ends.

    Raises ``SettingError``, ``InputError``, ``JobError`` (nothing to cut, a tool that fits
    nowhere).
    """
    if progress is not None and not callable(progress):
        raise TypeError(f"progress: expected a function (stage, fraction), got {type(progress).__name__}")
    return RoughResult(_swarf.rough(job, progress, **settings))


def check(job: Job, gcode: str, name: str = "program.ngc", tool_diameter: Optional[float] = None, **settings: Any) -> dict:
    """Proves a program's G-code (swarf's or any other system's, LinuxCNC or GRBL dialect) on
    a 2.5D job as ``rough`` proves its own, and returns the report (dict): machining time,
    engagement, gouges, rapid collisions, rest. ``tool_diameter`` is the program's tool when
    it is not the job's; ``res`` and ``sim`` set the simulation. A program the reader refuses
    raises ``InputError`` naming ``name``, the line and the column."""
    return json.loads(_swarf.check(job, gcode, name, tool_diameter, **settings))


class ToolPlan:
    """What ``plan_tools`` found: ``programs`` (a list of (file name, G-code, ``Toolpath``),
    one per tool of the cheapest sequence, in order) and ``report`` (dict, as ``swarf plan``'s
    ``plan.json``)."""

    def __init__(self, programs: list, report_json: str) -> None:
        self.programs = [(name, gcode, Toolpath(arrays)) for name, gcode, arrays in programs]
        self.report: dict = json.loads(report_json)

    def write(self, folder: PathLike, report: str = "plan.json", inputs: Iterable[PathLike] = ()) -> None:
        """Writes the programs and the report into ``folder`` (made when missing) atomically."""
        folder = Path(folder)
        files = [(os.fspath(folder / name), gcode.encode()) for name, gcode, _ in self.programs]
        files.append((os.fspath(folder / report), (json.dumps(self.report, indent=2) + "\n").encode()))
        folder.mkdir(parents=True, exist_ok=True)
        _swarf.write_files(files, [os.fspath(p) for p in inputs])


def plan_tools(job: Job, tools: Union[PathLike, Mapping[str, Any]], **settings: Any) -> ToolPlan:
    """The cheapest sequence of tools for a 3D job from a tool database (paper 3), one program
    per tool, as ``swarf plan`` finds it. ``tools`` is the database's file or its data (a dict
    in the file's format). Keywords: ``decomposition`` (``"trim"``, ``"regions"``),
    ``exhaustive``, ``ramp_angle``, ``clearance``, ``simulate``, ``post``, and the job's
    overrides."""
    if isinstance(tools, Mapping):
        return ToolPlan(*_swarf.plan_tools(job, "tools.json", json.dumps(tools, default=_plain), **settings))
    return ToolPlan(*_swarf.plan_tools(job, os.fspath(tools), None, **settings))


def __getattr__(name: str) -> Any:
    # (the batch module imports Dask, which only batches need)
    if name == "batch":
        from .cluster import batch

        return batch
    raise AttributeError(f"module 'swarf' has no attribute {name!r}")
