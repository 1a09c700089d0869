"""FreeCAD's Adaptive operation as G-code, from the paths of libarea's Adaptive2d.

Run by FreeCAD's own interpreter (scripts/side_by_side.py does this):

    SWARF_FC_JOB=job.json freecadcmd -c "exec(open('scripts/freecad_program.py').read())"

`job.json` holds what FreeCAD's Path workbench keeps of an Adaptive operation after
`Adaptive2d.Execute` (its `AdaptiveOutputState`: per region the helix centre, the start point,
the paths with their motion types and the return motion), the operation's depths and heights,
the tool controller's feeds (mm/min) and spindle speed, and `out`, the G-code file to write.

The moves are made by FreeCAD's own `PathScripts.PathAdaptive.GenerateGCode` (FreeCAD 0.20),
which turns those paths into the operation's commands at every step-down, with the helix
entries, links and lifts a FreeCAD user gets; the commands are written as LinuxCNC G-code (feeds
from FreeCAD's mm/s to mm/min, arcs with incremental I and J as FreeCAD keeps them). The
operation's defaults are the Path workbench's (helix angle 5°, no cone, straight helix moves,
no lift distance); `GenerateGCode` reads them off stand-ins for the operation and its object,
so no document, model or Job is needed.
"""

import json
import os
import types


def _quantity(v):
    return types.SimpleNamespace(Value=float(v))


def _gcode(commands, spindle_rpm):
    lines = ["G21 G90 G17", "G0 Z%.4f" % commands["clearance"]]
    if spindle_rpm:
        lines.append("M3 S%.0f" % spindle_rpm)
    for c in commands["list"]:
        name = c.Name
        if name.startswith("("):
            continue
        words = [name]
        for k in ("X", "Y", "Z", "I", "J", "K"):
            if k in c.Parameters:
                words.append("%s%.4f" % (k, c.Parameters[k]))
        if "F" in c.Parameters and name != "G0":
            words.append("F%.1f" % (c.Parameters["F"] * 60.0))
        lines.append(" ".join(words))
    lines += ["M5", "M2"]
    return "\n".join(lines) + "\n"


def main():
    with open(os.environ["SWARF_FC_JOB"]) as f:
        job = json.load(f)
    import PathScripts.PathAdaptive as PathAdaptive

    op = types.SimpleNamespace(
        commandlist=[],
        horizFeed=job["feed"] / 60.0,
        vertFeed=job["vert_feed"] / 60.0,
        tool=types.SimpleNamespace(Diameter=job["tool_diameter"]),
    )
    obj = types.SimpleNamespace(
        StepDown=_quantity(job["step_down"]),
        StartDepth=_quantity(job["start_depth"]),
        FinalDepth=_quantity(job["final_depth"]),
        FinishDepth=_quantity(0.0),
        ClearanceHeight=_quantity(job["clearance_height"]),
        SafeHeight=_quantity(job["safe_height"]),
        LiftDistance=_quantity(0.0),
        HelixAngle=5.0,
        HelixConeAngle=0.0,
        UseHelixArcs=False,
    )
    PathAdaptive.GenerateGCode(op, obj, job["results"], 0.0)
    text = _gcode({"list": op.commandlist, "clearance": job["clearance_height"]}, job.get("spindle_rpm"))
    with open(job["out"], "w") as f:
        f.write(text)


main()
