"""A FreeCAD Path Job cleared by swarf and posted by FreeCAD's LinuxCNC post, headless.

Run by FreeCAD's own interpreter (test_freecad.py does this):

    SWARF_FC_OUT=/some/folder freecadcmd -c "exec(open('crates/swarf-py/tests/freecad_job.py').read())"

with the ``swarf`` package on PYTHONPATH. (``freecadcmd -c`` exits 1 on an uncaught exception;
``freecadcmd FILE.py`` prints it and exits 0, so the script records what happened in
``result.json`` either way and the test reads that.)

The part ($SWARF_FC_MODEL, ``pocket`` by default): a block 100 x 80 x 20 mm, x 0..100,
y 0..80, z 0..20 (top at z = 20), with a 60 x 40 mm pocket of 8 mm corner radius centred on it
(x 20..80, y 20..60), 6 mm deep (floor z = 14); the job's stock is the model's bounding box with
no margins. ``island``: a block 120 x 90 x 25 mm with an 80 x 60 mm pocket (10 mm corners)
10 mm deep (floor z = 15) round a Ø20 mm boss 7 mm high, a shallower Ø15 mm pocket 4 mm deep
(left as part: a case has one floor) and a drafted pocket (a cone, Ø12 at its floor z = 17 to
Ø18 at the top); the stock keeps FreeCAD's 1 mm margins, so it is 1 mm above the model's top.
The tool controller: a 6 mm end mill at 1000 mm/min (FreeCAD holds 16.667 mm/s), 300 mm/min
vertical, 10000 rpm, tool number 1.

Writes into $SWARF_FC_OUT: ``posted.ngc`` (the job posted by ``linuxcnc_post`` with
``--no-show-editor``), ``case.json`` (what ``swarf.freecad.case_from_job`` built), ``report.json``
(swarf's report from inside FreeCAD), ``job.FCStd`` (the document, saved and read back) and
``result.json`` (``ok``, timings, counts, and ``error`` with the traceback when it failed).
"""

import json
import os
import time
import traceback

T0 = time.time()
OUT = os.environ["SWARF_FC_OUT"]
MODEL = os.environ.get("SWARF_FC_MODEL", "pocket")
result = {"ok": False, "stage": "start"}


def _write(name, text):
    with open(os.path.join(OUT, name), "w") as f:
        f.write(text)


def _run():
    import FreeCAD
    import Part

    result["freecad_version"] = ".".join(FreeCAD.Version()[:3])
    result["stage"] = "model"
    doc = FreeCAD.newDocument("SwarfFreeCADTest")
    island = MODEL == "island"
    if island:
        block = Part.makeBox(120, 90, 25)
        cutter = Part.makeBox(80, 60, 10, FreeCAD.Vector(20, 15, 15))
        vertical = [e for e in cutter.Edges if abs(e.Vertexes[0].Z - e.Vertexes[1].Z) > 1e-6]
        cutter = cutter.makeFillet(10.0, vertical)
        boss = Part.makeCylinder(10, 7, FreeCAD.Vector(60, 45, 15))
        shallow = Part.makeCylinder(7.5, 4, FreeCAD.Vector(10, 10, 21))
        drafted = Part.makeCone(6, 9, 8, FreeCAD.Vector(108, 78, 17))
        shape = block.cut(cutter).fuse(boss).cut(shallow).cut(drafted).removeSplitter()
    else:
        block = Part.makeBox(100, 80, 20)
        cutter = Part.makeBox(60, 40, 10, FreeCAD.Vector(20, 20, 14))
        vertical = [e for e in cutter.Edges if abs(e.Vertexes[0].Z - e.Vertexes[1].Z) > 1e-6]
        cutter = cutter.makeFillet(8.0, vertical)
        shape = block.cut(cutter)
    model = doc.addObject("Part::Feature", "PocketBlock")
    model.Shape = shape
    doc.recompute()

    result["stage"] = "job"
    import PathScripts.PathJob as PathJob
    import PathScripts.PathToolController as PathToolController

    job = PathJob.Create("Job", [model])
    for k in ("ExtXneg", "ExtXpos", "ExtYneg", "ExtYpos", "ExtZneg", "ExtZpos"):
        if hasattr(job.Stock, k) and not island:  # (the island job keeps FreeCAD's 1 mm margins)
            setattr(job.Stock, k, 0.0)
    if not job.Tools.Group:
        job.Proxy.addToolController(PathToolController.Create())
    tc = job.Tools.Group[0]
    tc.Label = "TC: 6 mm end mill"
    tc.Tool.Diameter = 6.0
    tc.HorizFeed = FreeCAD.Units.Quantity("1000 mm/min")
    tc.VertFeed = FreeCAD.Units.Quantity("300 mm/min")
    tc.SpindleSpeed = 10000.0
    tc.ToolNumber = 1
    job.PostProcessor = "linuxcnc"
    job.PostProcessorArgs = "--no-show-editor"
    doc.recompute()
    sb = job.Stock.Shape.BoundBox
    result["stock_bounds"] = [sb.XMin, sb.YMin, sb.ZMin, sb.XMax, sb.YMax, sb.ZMax]
    result["horiz_feed_mm_per_s"] = tc.HorizFeed.Value

    result["stage"] = "swarf"
    import swarf
    import swarf.freecad as sfc

    result["swarf_module"] = swarf.__file__
    t = time.time()
    case = sfc.case_from_job(job)
    _write("case.json", json.dumps(case, indent=1))
    op = sfc.add_adaptive(job)
    doc.recompute()
    result["add_adaptive_s"] = time.time() - t
    names = [c.Name for c in op.Path.Commands]
    result["commands"] = len(names)
    result["command_counts"] = {n: names.count(n) for n in sorted(set(names)) if not n.startswith("(")}
    result["label2"] = op.Label2
    result["job_cycle_time"] = job.CycleTime
    result["op_in_job"] = op in job.Operations.Group
    result["op_tool_controller"] = op.ToolController.Label if op.ToolController else None
    _write("report.json", op.SwarfReport)

    result["stage"] = "post"
    import PathScripts.PathPost as PathPost
    from PathScripts.PathPostProcessor import PostProcessor

    postlist = PathPost.CommandPathPost().buildPostList(job)
    result["post_objects"] = [[o.Label for o in sub] for sub in postlist]
    processor = PostProcessor.load(job.PostProcessor)
    posted = os.path.join(OUT, "posted.ngc")
    t = time.time()
    processor.export(postlist[0], posted, job.PostProcessorArgs)
    result["post_s"] = time.time() - t
    result["posted"] = posted

    result["stage"] = "save"
    fcstd = os.path.join(OUT, "job.FCStd")
    op_name = op.Name
    doc.saveAs(fcstd)
    FreeCAD.closeDocument(doc.Name)
    doc2 = FreeCAD.openDocument(fcstd)
    doc2.recompute()
    op2 = doc2.getObject(op_name)
    result["commands_after_reload"] = len(op2.Path.Commands)
    result["active_after_reload"] = op2.Active
    FreeCAD.closeDocument(doc2.Name)
    result["stage"] = "done"
    result["ok"] = True


try:
    _run()
except BaseException as e:  # noqa: BLE001 - recorded for the test, then raised
    result["error"] = "%s: %s" % (type(e).__name__, e)
    result["traceback"] = traceback.format_exc()
    raise
finally:
    result["script_s"] = time.time() - T0
    _write("result.json", json.dumps(result, indent=1))
