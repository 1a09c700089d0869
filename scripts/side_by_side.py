#!/usr/bin/env python3
"""swarf and FreeCAD's Adaptive (libarea's Adaptive2d) side by side on the example cases.

    cargo build --release
    python3 scripts/side_by_side.py [--repeat 3] [--swarf target/release/swarf] [--keep DIR] [CASE.json ...]

For every case it runs the command a user runs, `swarf rough CASE -o OUT.ngc --report R.json`,
as a whole process (reading, planning, proving on the simulator, writing), and keeps the best
wall time of `--repeat` runs; the report gives the planning and proof times, the program's
machining time, its cutting length and its largest engagement outside the entry bores.

When FreeCAD's libarea binding imports (Debian: `apt-get install freecad-python3`, which puts
`area.so` in /usr/lib/freecad-python3/lib), it also times `Adaptive2d.Execute` on the same
geometry, tool and stepover as swarf's report (the planning alone, best of `--repeat`, a fresh Adaptive2d each),
the way FreeCAD's Path workbench calls it: the stock outline as the stock paths; for a pocket
(`peer_mode: inside`) the pocket wall and its islands as the paths, otherwise the part. Its
cutting length is the length of its cutting paths times swarf's number of levels (FreeCAD
repeats its one 2D path at every level). Without FreeCAD the script prints swarf's columns.

When `freecadcmd` is there too, FreeCAD's program is made from those paths by FreeCAD's own
`PathAdaptive.GenerateGCode` (scripts/freecad_program.py: the helix entries from the stock top
at every level, links and lifts as a FreeCAD user gets them) at swarf's levels, clearance 5 mm
and safe height 3 mm above the stock, the case's feed, and both programs are replayed by
`swarf view` on the same simulator: machining time, largest and mean engagement outside the
entry bores (a move that goes down while it moves sideways reads as an entry, in either
program) and gouges. `--keep DIR` keeps FreeCAD's programs, for any other checker.

Standard library only. Prints a Markdown table on stdout.
"""

import argparse
import glob
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def load_area():
    """FreeCAD's libarea binding, or None."""
    for d in ("/usr/lib/freecad-python3/lib", "/usr/lib/freecad/lib"):
        if os.path.isdir(d) and d not in sys.path:
            sys.path.append(d)
    try:
        import area  # FreeCAD's libarea binding

        return area
    except ImportError:
        return None


def ring(points):
    """A ring as a list of float (x, y), without a closing vertex (the library closes it)."""
    pts = [(float(p[0]), float(p[1])) for p in points]
    return pts[:-1] if len(pts) > 1 and pts[0] == pts[-1] else pts


def rings(items):
    """The outer rings (and holes) of a case's part or fixture list, as lists of (x, y)."""
    out = []
    for it in items:
        if isinstance(it, dict):
            out.append(ring(it["outer"]))
            out += [ring(h) for h in it.get("holes", [])]
        else:
            out.append(ring(it))
    return out


def freecad_inputs(case):
    """(stock paths, paths, operation) for Adaptive2d.Execute."""
    stock = ring(case["stock"])
    items = list(case.get("part", [])) + list(case.get("fixtures", []))
    mode = case.get("peer_mode", "outside")
    if mode != "inside":
        return [stock], rings(items), "outside"
    xs = [p[0] for p in stock]
    ys = [p[1] for p in stock]
    box = (min(xs), min(ys), max(xs), max(ys))
    walls, islands = [], []
    for it in items:
        outer = ring(it["outer"] if isinstance(it, dict) else it)
        ox = [p[0] for p in outer]
        oy = [p[1] for p in outer]
        frame = min(ox) <= box[0] and min(oy) <= box[1] and max(ox) >= box[2] and max(oy) >= box[3]
        if isinstance(it, dict) and frame:
            walls += [ring(h) for h in it.get("holes", [])]
        elif box[0] <= min(ox) and max(ox) <= box[2] and box[1] <= min(oy) and max(oy) <= box[3]:
            islands += rings([it])
    wall = walls[0] if len(walls) == 1 else stock
    return [stock], [wall] + islands, "inside"


def freecad_run(area, case, stepover, repeat):
    """Best planning time of Adaptive2d.Execute at `stepover` (a fraction of the diameter), s,
    the length of its cutting paths, mm, and its results as the Path workbench keeps them."""
    stock_paths, paths, mode = freecad_inputs(case)
    d = float(case["tool"]["diameter"])
    best, length = math.inf, 0.0
    for _ in range(repeat):
        a2d = area.Adaptive2d()
        a2d.toolDiameter = d
        a2d.stepOverFactor = stepover
        a2d.tolerance = 0.1
        a2d.stockToLeave = float(case.get("allowance", 0.0))
        # the Path workbench's defaults (the binding's own forceInsideOut is True)
        a2d.forceInsideOut = False
        a2d.finishingProfile = True
        a2d.helixRampDiameter = 0.0
        a2d.keepToolDownDistRatio = 3.0
        a2d.opType = (
            area.AdaptiveOperationType.ClearingInside if mode == "inside" else area.AdaptiveOperationType.ClearingOutside
        )
        # (the library prints its progress on the C stdout: keep the table clean)
        sys.stdout.flush()
        saved = os.dup(1)
        os.dup2(2, 1)
        try:
            t0 = time.perf_counter()
            results = a2d.Execute(stock_paths, paths, lambda _: False)
            best = min(best, time.perf_counter() - t0)
        finally:
            os.dup2(saved, 1)
            os.close(saved)
        cutting = int(area.AdaptiveMotionType.Cutting)
        length = 0.0
        for r in results:
            for mt, pts in r.AdaptivePaths:
                if int(mt) == cutting:
                    pts = [tuple(p) for p in pts]
                    length += sum(math.dist(a, b) for a, b in zip(pts, pts[1:]))
    kept = [
        {
            "HelixCenterPoint": list(r.HelixCenterPoint),
            "StartPoint": list(r.StartPoint),
            "AdaptivePaths": [[int(mt), [list(p) for p in pts]] for mt, pts in r.AdaptivePaths],
            "ReturnMotionType": int(r.ReturnMotionType),
        }
        for r in results
    ]
    return best, length, kept


def freecad_program(case, results, report, out, tmp):
    """Writes FreeCAD's program (scripts/freecad_program.py, run by `freecadcmd`) at swarf's
    levels, clearance 5 mm and safe height 3 mm above the stock, the case's feed for both
    directions; True when it was written."""
    exe = shutil.which("freecadcmd")
    if exe is None or not results:
        return False
    top = float(case.get("stock_top", 0.0))
    levels = report["levels"]
    feed = float(case.get("feed_default", 1000.0))
    job = {
        "results": results,
        "start_depth": top,
        "final_depth": levels[-1],
        # (a hair more, so that FreeCAD's own division gives swarf's levels)
        "step_down": (top - levels[-1]) / len(levels) + 1e-6,
        "clearance_height": top + 5.0,
        "safe_height": top + 3.0,
        "feed": feed,
        "vert_feed": feed,
        "tool_diameter": float(case["tool"]["diameter"]),
        "spindle_rpm": case.get("spindle_rpm"),
        "out": out,
    }
    path = os.path.join(tmp, "freecad_job.json")
    with open(path, "w") as f:
        json.dump(job, f)
    script = os.path.join(HERE, "freecad_program.py")
    env = dict(os.environ, SWARF_FC_JOB=path)
    subprocess.run([exe, "-c", "exec(open(%r).read())" % script], env=env, check=True, capture_output=True)
    return os.path.exists(out)


VIEW_LINE = re.compile(
    r"([\d.]+) min, engagement max / p95 / mean ([\d.]+)° / ([\d.]+)° / ([\d.]+)°, gouges (\d+)"
)


def proven(exe, program, case_path, tmp):
    """(machining min, max, p95 and mean engagement °, gouges) of any program on the case, by
    `swarf view` (swarf's simulator, the same replay for every program)."""
    res = subprocess.run(
        [exe, "view", program, "--case", case_path, "-o", os.path.join(tmp, "view.html")],
        check=True,
        capture_output=True,
        text=True,
    )
    m = VIEW_LINE.search(res.stdout + res.stderr)
    if m is None:
        raise RuntimeError("swarf view said: " + res.stdout + res.stderr)
    return float(m[1]), float(m[2]), float(m[3]), float(m[4]), int(m[5])


def swarf_run(exe, path, repeat, tmp):
    """Best wall time of the whole command, s, and its report."""
    name = os.path.splitext(os.path.basename(path))[0]
    out = os.path.join(tmp, name + ".ngc")
    rep = os.path.join(tmp, name + ".json")
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run([exe, "rough", path, "-o", out, "--report", rep], check=True, capture_output=True)
        best = min(best, time.perf_counter() - t0)
    with open(rep) as f:
        return best, json.load(f)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("cases", nargs="*", help="case files (default: examples/cases/*.json)")
    ap.add_argument("--swarf", default=os.path.join(ROOT, "target", "release", "swarf"))
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--keep", metavar="DIR", help="copy FreeCAD's programs (NAME.freecad.ngc) into DIR")
    a = ap.parse_args()
    if a.keep:
        os.makedirs(a.keep, exist_ok=True)
    cases = a.cases or sorted(glob.glob(os.path.join(ROOT, "examples", "cases", "*.json")))
    area = load_area()
    if area is None:
        print("(FreeCAD's libarea does not import: swarf's columns only)", file=sys.stderr)
    head = "| case | swarf run s | planned s | proven s | swarf min | efficiency | swarf cut m | max engagement (ref) |"
    rule = "|---|---|---|---|---|---|---|---|"
    if area is not None:
        head += " FreeCAD plan s | run / FreeCAD | FreeCAD cut m | cut / FreeCAD |"
        rule += "---|---|---|---|"
    program = area is not None and shutil.which("freecadcmd") is not None
    if program:
        head += " FreeCAD min | min / FreeCAD | engagement max swarf / FreeCAD | mean swarf / FreeCAD | gouges swarf / FreeCAD |"
        rule += "---|---|---|---|---|"
    print(head)
    print(rule)
    with tempfile.TemporaryDirectory() as tmp:
        for path in cases:
            with open(path) as f:
                case = json.load(f)
            name = os.path.splitext(os.path.basename(path))[0]
            run_s, r = swarf_run(a.swarf, path, a.repeat, tmp)
            cut_m = r["cut_length_mm"] / 1000.0
            row = "| %s | %.2f | %.2f | %.2f | %.2f | %.0f %% | %.2f | %.0f (%.0f) |" % (
                name,
                run_s,
                r["compute_s"],
                r["simulate_s"],
                r["time_min"],
                100.0 * r.get("efficiency", 0.0),
                cut_m,
                r["engagement_deg"]["max"],
                r["engagement_ref_deg"],
            )
            if area is not None:
                fc_s, fc_len, results = freecad_run(area, case, r["stepover"], a.repeat)
                fc_m = fc_len * len(r["levels"]) / 1000.0
                if fc_m > 0:
                    row += " %.2f | %.2f | %.2f | %.2f |" % (fc_s, run_s / fc_s, fc_m, cut_m / fc_m)
                else:
                    row += " %.2f | no path | 0 | no path |" % fc_s
            if program:
                fc_ngc = os.path.join(tmp, name + ".freecad.ngc")
                if fc_m > 0 and freecad_program(case, results, r, fc_ngc, tmp):
                    own = proven(a.swarf, os.path.join(tmp, name + ".ngc"), path, tmp)
                    fc = proven(a.swarf, fc_ngc, path, tmp)
                    if a.keep:
                        shutil.copy(fc_ngc, os.path.join(a.keep, name + ".freecad.ngc"))
                    row += " %.2f | %.2f | %.0f / %.0f | %.1f / %.1f | %d / %d |" % (
                        fc[0],
                        own[0] / fc[0],
                        own[1],
                        fc[1],
                        own[3],
                        fc[3],
                        own[4],
                        fc[4],
                    )
                else:
                    row += " no path | | | | |"
            print(row, flush=True)


if __name__ == "__main__":
    main()
