"""swarf inside FreeCAD: adaptive clearing for a FreeCAD Path Job.

This module runs inside FreeCAD (0.20 and later: it needs FreeCAD's ``FreeCAD``, ``Part`` and
``Path`` modules and the Path workbench's ``PathScripts``). It reads a Job's model, stock and
first tool controller into a swarf 2.5D case (:func:`case_from_job`), runs swarf's adaptive
clearing on it, and adds the toolpath to the Job as a Path object (:func:`add_adaptive`), so that
FreeCAD's own post-processors write the G-code. :func:`path_from_gcode` turns swarf's G-code into
FreeCAD Path commands.

Units: FreeCAD holds lengths in mm and speeds in mm/s; swarf's cases and G-code use mm and
mm/min. Feeds in a FreeCAD ``Path.Command`` are mm/s (FreeCAD's posts multiply by 60 when they
write mm/min), so :func:`path_from_gcode` divides swarf's F words by 60.

Only the functions' FreeCAD calls need FreeCAD: importing this module elsewhere works, and
calling them there raises an ImportError that says so.
"""

import json
import re

__all__ = ["case_from_job", "path_from_gcode", "add_adaptive", "gcode_commands"]

# The default chord tolerance (mm) for curved edges of the part's cross-section.
DEFLECTION_MM = 0.01


def _freecad():
    """FreeCAD's modules (FreeCAD, Part, Path), or an ImportError that says where this runs."""
    try:
        import FreeCAD
        import Part
        import Path
    except ImportError as e:  # pragma: no cover - depends on the interpreter
        raise ImportError(
            "swarf.freecad runs inside FreeCAD (it needs FreeCAD's FreeCAD, Part and Path modules): "
            "use it from FreeCAD's Python console, a macro or freecadcmd, not from a plain Python"
        ) from e
    return FreeCAD, Part, Path


def _value(q, unit=None):
    """A FreeCAD quantity (or a plain number) as a float, in `unit` when it is a quantity."""
    if hasattr(q, "getValueAs") and unit is not None:
        return float(q.getValueAs(unit))
    return float(getattr(q, "Value", q))


# ---- the case ----------------------------------------------------------------------------------


def _model_shapes(job):
    shapes = []
    for o in getattr(job.Model, "Group", []) if getattr(job, "Model", None) else []:
        s = getattr(o, "Shape", None)
        if s is not None and not s.isNull():
            shapes.append(s)
    if not shapes:
        raise ValueError("the job %r has no model with a shape (Job.Model.Group)" % job.Label)
    return shapes


def _upward_floors(shapes, top, tol):
    """The z of every upward-facing horizontal planar face below `top`."""
    zs = []
    for s in shapes:
        for f in s.Faces:
            bb = f.BoundBox
            if bb.ZLength > tol or bb.ZMax >= top - tol:
                continue
            try:
                if not f.Surface.isPlanar():
                    continue
            except Exception:
                if "Plane" not in type(f.Surface).__name__:
                    continue
            u0, u1, v0, v1 = f.ParameterRange
            n = f.normalAt(0.5 * (u0 + u1), 0.5 * (v0 + v1))
            if n.z > 1.0 - 1e-6:
                zs.append(0.5 * (bb.ZMin + bb.ZMax))
    return zs


def _ring(wire, deflection):
    """The points [[x, y], ...] of a closed wire, curved edges within `deflection` (mm)."""
    try:
        pts = wire.discretize(Deflection=deflection)
    except Exception:
        pts = []
    if len(pts) < 3:  # a wire of one closed edge, or a discretizer that gave up: edge by edge
        pts = []
        for e in wire.OrderedEdges:
            p = e.discretize(Deflection=deflection)
            pts.extend(p if not pts else p[1:])
    ring = [[round(p.x, 6), round(p.y, 6)] for p in pts]
    while len(ring) > 1 and abs(ring[0][0] - ring[-1][0]) < 1e-6 and abs(ring[0][1] - ring[-1][1]) < 1e-6:
        ring.pop()
    # drop repeated points (the joints of edges)
    out = []
    for p in ring:
        if not out or abs(out[-1][0] - p[0]) > 1e-9 or abs(out[-1][1] - p[1]) > 1e-9:
            out.append(p)
    return out


def _section_faces(shapes, z):
    """The faces of the shapes' cross-section at height z (holes nested), as one list."""
    FreeCAD, Part, _ = _freecad()
    faces = []
    for s in shapes:
        wires = [w for w in s.slice(FreeCAD.Vector(0, 0, 1), z) if w.isClosed()]
        if not wires:
            continue
        made = Part.makeFace(wires, "Part::FaceMakerBullseye")
        faces.extend(made.Faces)
    return faces


def case_from_job(
    job,
    floor=None,
    engagement_deg=None,
    stepover=None,
    stepdown=None,
    allowance=None,
    deflection=DEFLECTION_MM,
):
    """Build a swarf 2.5D case (a dict in the format of swarf's case files) from a FreeCAD Path Job.

    - ``stock``: the XY rectangle of the bounding box of ``job.Stock``'s shape (a cylindrical
      stock becomes its bounding rectangle); ``stock_top``: the stock's top (z max).
    - ``part``: the material that must stay: the cross-sections of the job's models
      (``job.Model.Group``, each model sliced on its own) from just above the floor up to their
      top (at every vertex height, just above and below it and half-way to the next), as
      ``[{"outer": [[x, y], ...], "holes": [[[x, y], ...], ...]}, ...]``, which swarf unions;
      straight edges give their end points, curved ones are discretized within ``deflection``
      mm. The part is the same at every level (2.5D), so a wall that leans or has a fillet is
      taken at its widest, which leaves stock on it rather than gouging it. Stock outside the models (a stock with margins) is cleared
      down to the floor too. ``part_top``: the top of the models, or the stock's where the
      stock is higher: a 2.5D case keeps the part's outline at every level, so the stock above
      the models' top is not faced (a warning says so; FreeCAD's Face operation does that).
    - ``floor``: the depth to clear to. Unless given, the z of the deepest upward-facing
      horizontal planar face of the models below their top (a pocket's floor); without one (a
      through pocket, or a model without pockets) the models' bottom. A case has one floor:
      with pockets at several depths the shallower ones are part material at the deepest
      floor and stay uncut; clear them with another case (``floor=`` their depth), which
      clears the deeper pockets down to that depth too.
    - ``tool``: ``{"diameter": D, "type": "flat", "number": N}`` from the job's first tool
      controller (``job.Tools.Group[0]``); swarf cuts with flat end mills only, and a tool
      whose shape is not an end mill gets a warning on FreeCAD's console.
    - ``feed_default`` (mm/min) from the controller's ``HorizFeed``, ``rapid_rate`` (mm/min) from
      its ``HorizRapid``, ``spindle_rpm`` from its ``SpindleSpeed``: each only where it is above 0
      (otherwise swarf's default holds). ``VertFeed`` has no counterpart in swarf: its entries
      are helices and ramps at the cutting feed.
    - ``units``: ``"mm"`` (FreeCAD's internal unit, whatever its display units).
    - ``stepdown`` (mm): as given, or one tool diameter (swarf's default for a part read on its
      own, ``DEFAULT_STEPDOWN_FRACTION`` of the diameter).
    - ``engagement_deg``, ``stepover`` (fraction of the diameter) and ``allowance`` (mm) when
      given.

    Raises ValueError when the job has no model or tool controller, when the floor is not below
    the stock's top, or when there is nothing to cut (the models cover the stock and reach its
    top).
    """
    FreeCAD, Part, _ = _freecad()
    tol = 1e-6
    shapes = _model_shapes(job)
    if getattr(job, "Stock", None) is None or job.Stock.Shape.isNull():
        raise ValueError("the job %r has no stock (Job.Stock)" % job.Label)
    sb = job.Stock.Shape.BoundBox
    mb = FreeCAD.BoundBox()
    for s in shapes:
        mb.add(s.BoundBox)
    part_top = mb.ZMax
    stock_top = sb.ZMax

    if floor is None:
        floors = _upward_floors(shapes, part_top, 1e-4)
        floor = min(floors) if floors else mb.ZMin
    floor = float(floor)
    if floor >= stock_top - tol:
        raise ValueError(
            "nothing to cut in job %r: the floor z %.4g mm is not below the stock top z %.4g mm"
            % (job.Label, floor, stock_top)
        )

    # the part is what stays at any height from the floor up (2.5D: one outline for every
    # level): the sections just above the floor, just above and below every vertex height up
    # to the top, and half-way between them (where a curved wall may reach out furthest),
    # which swarf unions; a wall that leans over the pocket is kept whole, not gouged
    above = sorted({round(v.Z, 9) for s in shapes for v in s.Vertexes if floor + 1e-7 < v.Z <= part_top + 1e-9})
    eps = min(0.01, 0.5 * (above[0] - floor)) if above else 0.01
    heights = [floor + eps]
    for a, b in zip([floor] + above, above):
        e = min(0.01, 0.25 * (b - a))
        heights += [a + e, 0.5 * (a + b), b - e]
    heights = sorted({round(h, 9) for h in heights if floor < h < part_top})[:200] or [floor + eps]
    faces = [f for h in heights for f in _section_faces(shapes, h)]
    part = []
    for f in faces:
        outer = _ring(f.OuterWire, deflection)
        if len(outer) < 3:
            continue
        holes = []
        for w in f.Wires:
            if w.isSame(f.OuterWire):
                continue
            r = _ring(w, deflection)
            if len(r) >= 3:
                holes.append(r)
        poly = {"outer": outer, "holes": holes}
        if poly not in part:  # (a vertical wall gives the same section at every height)
            part.append(poly)

    stock = [[sb.XMin, sb.YMin], [sb.XMax, sb.YMin], [sb.XMax, sb.YMax], [sb.XMin, sb.YMax]]
    if sb.XLength <= tol or sb.YLength <= tol:
        raise ValueError("the stock of job %r has no area in XY" % job.Label)
    # anything to cut? stock beside the part, or stock above the part's top
    rect = Part.makePlane(sb.XLength, sb.YLength, FreeCAD.Vector(sb.XMin, sb.YMin, floor + eps))
    free = rect.cut(Part.makeCompound(faces)).Area if faces else rect.Area
    if free < 1e-6 and stock_top <= part_top + tol:
        raise ValueError(
            "nothing to cut in job %r: the models cover the stock from z %.4g mm up to its top"
            % (job.Label, floor)
        )

    if stock_top > part_top + 1e-6:
        # a 2.5D case keeps the part's outline at every level: the stock above the models' top is
        # not faced (FreeCAD's Face operation does that), and the case says so by putting the
        # part's top at the stock's, so that no one counts that layer as material left behind
        FreeCAD.Console.PrintWarning(
            "swarf: the stock's top (z %.4g mm) is above the model's (z %.4g mm): the %.4g mm between are "
            "not faced by this operation; face them first (Path Face)\n"
            % (stock_top, part_top, stock_top - part_top)
        )
    tcs = list(getattr(job.Tools, "Group", [])) if getattr(job, "Tools", None) else []
    if not tcs:
        raise ValueError("the job %r has no tool controller (Job.Tools.Group is empty)" % job.Label)
    tc = tcs[0]
    tool = tc.Tool
    diameter = _value(tool.Diameter, "mm")
    if not diameter > 0:
        raise ValueError("the tool of %r has diameter %s: it must be positive" % (tc.Label, diameter))
    shape = str(getattr(tool, "BitShape", "") or getattr(tool, "ToolType", ""))
    if shape and not re.search(r"endmill|end_mill|EndMill|SlotCutter", shape, re.I):
        FreeCAD.Console.PrintWarning(
            "swarf: tool %r is a %s; swarf plans for a flat end mill of diameter %g mm\n"
            % (tc.Label, shape, diameter)
        )
    case = {
        "units": "mm",
        "stock": stock,
        "stock_top": stock_top,
        "part": part,
        "part_top": max(part_top, stock_top),
        "floor": floor,
        "tool": {"diameter": diameter, "type": "flat"},
    }
    number = int(getattr(tc, "ToolNumber", 0) or 0)
    if number >= 1:
        case["tool"]["number"] = number
    feed = _value(tc.HorizFeed, "mm/min") if hasattr(tc, "HorizFeed") else 0.0
    if feed > 0:
        case["feed_default"] = round(feed, 6)
    rapid = _value(tc.HorizRapid, "mm/min") if hasattr(tc, "HorizRapid") else 0.0
    if rapid > 0:
        case["rapid_rate"] = round(rapid, 6)
    rpm = float(getattr(tc, "SpindleSpeed", 0.0) or 0.0)
    if rpm > 0:
        case["spindle_rpm"] = rpm
    if engagement_deg is not None:
        case["engagement_deg"] = float(engagement_deg)
    if stepover is not None:
        case["stepover"] = float(stepover)
    if stepdown is None:
        # (as swarf's own default for a part read on its own: one tool diameter a level)
        from swarf._swarf import DEFAULT_STEPDOWN_FRACTION

        stepdown = DEFAULT_STEPDOWN_FRACTION * diameter
    case["stepdown"] = float(stepdown)
    if allowance is not None:
        case["allowance"] = float(allowance)
    return case


# ---- G-code to Path ------------------------------------------------------------------------

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")
_MOTION = {"G0": "G0", "G00": "G0", "G1": "G1", "G01": "G1", "G2": "G2", "G02": "G2", "G3": "G3", "G03": "G3"}
# words dropped: FreeCAD's post and the tool controller write their own
_DROPPED_G = {
    "G17", "G21", "G20", "G90", "G94", "G40", "G49", "G80", "G54", "G43", "G64", "G61", "G61.1",
    "G90.1",
}
_DROPPED_M = {"M2", "M02", "M30", "M3", "M03", "M4", "M04", "M5", "M05", "M6", "M06", "M7", "M07",
              "M8", "M08", "M9", "M09", "M0", "M00", "M1", "M01"}
_KEPT_AXES = "XYZIJKR"


def _num_text(v):
    return ("%.6f" % v).rstrip("0").rstrip(".")


def gcode_commands(gcode, comments=True):
    """Parse G-code into ``[(name, {word: value})]`` in FreeCAD's conventions (no FreeCAD needed).

    The pure-Python part of :func:`path_from_gcode`: coordinates in mm (G20 programs scaled by
    25.4), feeds in mm/s, every feed move with its F, comments as ``("(text)", {})`` when
    ``comments`` is true and they come after the first motion. See :func:`path_from_gcode` for
    what is kept and what is dropped.
    """
    out = []
    scale = 1.0
    mode = None  # modal motion G0..G3
    feed = None  # mm/min as written, in the program's units
    moved = False
    for lineno, raw in enumerate(gcode.splitlines(), 1):
        line = raw.strip()
        notes = re.findall(r"\(([^)]*)\)", line)
        line = re.sub(r"\([^)]*\)", " ", line)
        if ";" in line:
            notes.append(line.split(";", 1)[1].strip())
            line = line.split(";", 1)[0]
        line = line.strip()
        if line.startswith("/"):
            line = line[1:]
        if comments and moved:
            for n in notes:
                n = n.replace("(", "[").replace(")", "]").strip()
                if n:
                    out.append(("(%s)" % n, {}))
        if not line or line == "%":
            continue
        words = _WORD.findall(line)
        rest = _WORD.sub(" ", line).strip()
        if rest:
            raise ValueError("G-code line %d: cannot read %r in %r" % (lineno, rest, raw))
        g_words = []
        params = {}
        other = []
        for letter, text in words:
            letter = letter.upper()
            if letter == "G":
                g = "G" + (text.rstrip("0").rstrip(".") if "." in text else str(int(float(text))))
                g_words.append(g)
            elif letter == "M":
                other.append("M" + str(int(float(text))))
            elif letter == "N":
                continue
            else:
                params[letter] = float(text)
        motion_here = None
        dwell = False
        for g in g_words:
            if g in ("G20", "G21"):
                scale = 25.4 if g == "G20" else 1.0
            if g in _MOTION:
                motion_here = _MOTION[g]
            elif g == "G4":
                dwell = True
            elif g in _DROPPED_G:
                continue
            else:
                raise ValueError(
                    "G-code line %d: %s is not one swarf.freecad turns into Path commands (%r)"
                    % (lineno, g, raw.strip())
                )
        for m in other:
            if m not in _DROPPED_M:
                raise ValueError("G-code line %d: %s is not one swarf.freecad handles (%r)" % (lineno, m, raw.strip()))
        if "F" in params:
            feed = params.pop("F") * scale
        # S, T, H, D, P of dropped words (spindle, tool change, offsets, blending)
        if dwell:
            out.append(("G4", {"P": params.get("P", 0.0)}))
            continue
        for k in ("S", "T", "H", "D", "Q"):
            params.pop(k, None)
        if motion_here is not None:
            mode = motion_here
        axes = {k: v * scale for k, v in params.items() if k in _KEPT_AXES}
        unknown = sorted(set(params) - set(_KEPT_AXES) - {"P"})
        if unknown:
            raise ValueError("G-code line %d: words %s are not read (%r)" % (lineno, ",".join(unknown), raw.strip()))
        if "P" in params and motion_here is not None:
            raise ValueError("G-code line %d: P on a motion (%r): multi-turn arcs are not read" % (lineno, raw.strip()))
        if not axes:
            continue
        if mode is None:
            raise ValueError("G-code line %d: axis words before any motion mode (%r)" % (lineno, raw.strip()))
        if mode != "G0" and feed is not None:
            axes["F"] = feed / 60.0
        out.append((mode, axes))
        moved = True
    return out


def path_from_gcode(gcode, comments=True):
    """Turn swarf's G-code (LinuxCNC or GRBL dialect) into a FreeCAD ``Path.Path``.

    Kept, as ``Path.Command``'s: the motions G0, G1, G2 and G3 with their X Y Z I J K (R) words
    (arcs stay arcs, I and J relative to the start as in the G-code; a line with axis words but
    no G word takes the modal motion), G4 dwells, and comments after the first motion (the
    levels, entries, plunges), as ``"(text)"`` commands, unless ``comments`` is false.
    F: every feed move (G1, G2, G3) carries the modal feed, converted from the G-code's mm/min
    to FreeCAD's mm/s (FreeCAD's posts multiply by 60 again and write it where it is given);
    G0 carries none.

    Dropped, because FreeCAD's post, the job or the tool controller writes its own: the
    preamble and modal settings (G17 G21 G90 G94 G40 G49 G80 G54 G61 G90.1), LinuxCNC's
    blending ``G64 P…`` (put it in the post's preamble if you want it), the tool change
    (T… M6, G43 H…), the spindle (S… M3/M4, M5), coolant (M7 M8 M9, see the operation's
    CoolantMode), pauses and the program end (M0 M1 M2 M30), line numbers, and the comments
    before the first motion (the program's header: the summary is on the object that
    :func:`add_adaptive` makes). G20 programs are scaled to mm. Incremental distance (G91),
    other arc planes (G18, G19), cutter compensation and other codes raise ValueError.
    """
    _, _, Path = _freecad()
    return Path.Path([Path.Command(name, params) for name, params in gcode_commands(gcode, comments)])


# ---- the operation ---------------------------------------------------------------------------

_CASE_KEYS = ("floor", "engagement_deg", "stepover", "stepdown", "allowance", "deflection")


def _hms(minutes):
    s = int(round(minutes * 60.0))
    return "%02d:%02d:%02d" % (s // 3600, (s // 60) % 60, s % 60)


def _summary(report):
    parts = []
    t = report.get("time_min")
    if t is not None:
        parts.append("%.2f min" % t)
    c = report.get("cut_length_mm")
    if c is not None:
        parts.append("cut %.2f m" % (c / 1000.0))
    e = (report.get("engagement_deg") or {}).get("max")
    if e is not None:
        parts.append("max engagement %.0f deg" % e)
    g = report.get("gouges")
    if g is not None:
        parts.append("gouges %d" % g)
    return "swarf adaptive: " + (", ".join(parts) if parts else "not simulated")


def _add_prop(obj, kind, name, group, doc):
    if not hasattr(obj, name):
        obj.addProperty(kind, name, group, doc)


def add_adaptive(job, name="SwarfAdaptive", **settings):
    """Add swarf's adaptive clearing of `job` to it as a Path object, and return the object.

    Builds the case with :func:`case_from_job` (the keywords ``floor``, ``engagement_deg``,
    ``stepover``, ``stepdown``, ``allowance`` and ``deflection`` go there), runs
    ``swarf.rough(swarf.Job.from_dict(case, name=job.Label), strategy="adaptive", **rest)`` with
    the other keywords, and adds a ``Path::FeaturePython`` named `name` to ``job.Operations``
    whose ``Path`` is :func:`path_from_gcode` of swarf's G-code. The object has the properties
    FreeCAD's post and job read: ``Active`` (true), ``ToolController`` (the job's first tool
    controller, so the post writes its tool change and spindle start before the path) and
    ``CycleTime`` (swarf's time estimate, HH:MM:SS, which the job adds up); and swarf's
    figures: ``Comment`` and ``Label2`` (a one-line summary), ``SwarfTimeMin``,
    ``SwarfCutLength``, ``SwarfMaxEngagement``, ``SwarfGouges``, ``SwarfReport`` (the whole
    report, JSON) and ``SwarfCase`` (the case, JSON, to rerun or check it outside FreeCAD).

    The object has no Python proxy: a saved document opens without swarf installed, and a
    recompute keeps the path as it is. To update it after changing the model, delete it and run
    this again.
    """
    FreeCAD, _, _ = _freecad()
    import swarf

    case_kw = {k: settings.pop(k) for k in _CASE_KEYS if k in settings}
    case = case_from_job(job, **case_kw)
    result = swarf.rough(swarf.Job.from_dict(case, name=job.Label), strategy="adaptive", **settings)
    report = dict(result.report)
    path = path_from_gcode(result.gcode)

    doc = job.Document
    obj = doc.addObject("Path::FeaturePython", name)
    _add_prop(obj, "App::PropertyBool", "Active", "Path", "Make False, to prevent operation from generating code")
    _add_prop(obj, "App::PropertyLink", "ToolController", "Path", "The tool controller the path is cut with")
    _add_prop(obj, "App::PropertyString", "CycleTime", "Path", "Operations Cycle Time Estimation (swarf)")
    _add_prop(obj, "App::PropertyString", "Comment", "Path", "An optional comment for this Operation")
    _add_prop(obj, "App::PropertyFloat", "SwarfTimeMin", "Swarf", "Machining time, min (swarf's estimate)")
    _add_prop(obj, "App::PropertyLength", "SwarfCutLength", "Swarf", "Length of the cutting moves")
    _add_prop(obj, "App::PropertyFloat", "SwarfMaxEngagement", "Swarf", "Largest engagement, degrees (simulated)")
    _add_prop(obj, "App::PropertyInteger", "SwarfGouges", "Swarf", "Gouges into the part (simulated)")
    _add_prop(obj, "App::PropertyString", "SwarfReport", "Swarf", "swarf's report (JSON)")
    _add_prop(obj, "App::PropertyString", "SwarfCase", "Swarf", "The case swarf planned (JSON)")
    obj.Active = True
    tcs = list(job.Tools.Group)
    obj.ToolController = tcs[0] if tcs else None
    summary = _summary(report)
    obj.Comment = summary
    obj.Label2 = summary
    if report.get("time_min") is not None:
        obj.SwarfTimeMin = float(report["time_min"])
        obj.CycleTime = _hms(float(report["time_min"]))
    if report.get("cut_length_mm") is not None:
        obj.SwarfCutLength = float(report["cut_length_mm"])
    emax = (report.get("engagement_deg") or {}).get("max")
    if emax is not None:
        obj.SwarfMaxEngagement = float(emax)
    if report.get("gouges") is not None:
        obj.SwarfGouges = int(report["gouges"])
    obj.SwarfReport = json.dumps(report)
    obj.SwarfCase = json.dumps(case)
    obj.Path = path

    proxy = getattr(job, "Proxy", None)
    if proxy is not None and hasattr(proxy, "addOperation"):
        proxy.addOperation(obj)
    else:
        job.Operations.addObject(obj)
    if FreeCAD.GuiUp and getattr(obj, "ViewObject", None) is not None:
        obj.ViewObject.Visibility = True
    return obj
