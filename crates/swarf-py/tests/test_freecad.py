"""swarf inside FreeCAD: a Path Job cleared by ``swarf.freecad.add_adaptive`` and posted by
FreeCAD's own LinuxCNC post (``freecad_job.py``, run headless by ``freecadcmd``).

Checks: the posted program has arcs and lines; LinuxCNC's interpreter ``rs274`` reads it without
a complaint and its feed length equals swarf's cut length; the posted moves are swarf's moves
(within 0.001 mm, feeds equal); and swarf's figures for the posted program (``swarf.check``)
equal those of swarf's own run on the same case (``swarf.rough``), and the report made inside
FreeCAD, within 1 %, with no gouges.

Skipped without ``freecadcmd`` on PATH unless ``SWARF_REQUIRE_FREECAD=1``; the interpreter
check is skipped without ``rs274`` unless ``SWARF_REQUIRE_RS274=1``.
"""

import json
import math
import os
import pathlib
import re
import shutil
import subprocess

import pytest

import swarf

HERE = pathlib.Path(__file__).resolve().parent
SCRIPT = HERE / "freecad_job.py"
OP_LABEL = "SwarfAdaptive"


def _tool(name, require_env, what, *others):
    found = next((p for p in map(shutil.which, (name,) + others) if p), None)
    if found is None:
        if os.environ.get(require_env) == "1":
            pytest.fail("%s=1 but %s (%s) is not on PATH" % (require_env, name, what))
        pytest.skip("%s (%s) is not on PATH; set %s=1 to make this a failure" % (name, what, require_env))
    return found


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """Runs freecad_job.py in freecadcmd once (the pocketed block); returns its output folder
    and result."""
    return _freecad_job(tmp_path_factory, "pocket")


@pytest.fixture(scope="module")
def run_island(tmp_path_factory):
    """freecad_job.py's second job: a pocket round an island, in FreeCAD's default stock."""
    return _freecad_job(tmp_path_factory, "island")


def _freecad_job(tmp_path_factory, model):
    freecadcmd = _tool("freecadcmd", "SWARF_REQUIRE_FREECAD", "FreeCAD's headless command line", "FreeCADCmd")
    base = tmp_path_factory.mktemp("freecad_" + model)
    pkg = base / "pkg"
    # only the swarf package, not the test interpreter's whole site-packages
    shutil.copytree(
        pathlib.Path(swarf.__file__).parent, pkg / "swarf", ignore=shutil.ignore_patterns("__pycache__")
    )
    out = base / "out"
    home = base / "home"  # FreeCAD's user settings: fresh, so no one's preferences change the run
    out.mkdir()
    home.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTHON") and k != "VIRTUAL_ENV"}
    env.update(
        PYTHONPATH=str(pkg), SWARF_FC_OUT=str(out), SWARF_FC_MODEL=model, HOME=str(home), PYTHONDONTWRITEBYTECODE="1"
    )
    proc = subprocess.run(
        [freecadcmd, "-c", "exec(open(%r).read())" % str(SCRIPT)],
        cwd=str(base),
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        timeout=600,
    )
    log = proc.stdout.decode("utf-8", "replace")
    (base / "freecad.log").write_text(log)
    result_file = out / "result.json"
    assert result_file.is_file(), "freecadcmd (exit %d) wrote no result; its output ends:\n%s" % (
        proc.returncode,
        log[-3000:],
    )
    result = json.loads(result_file.read_text())
    assert result["ok"], "in FreeCAD, at %s: %s\n%s" % (result["stage"], result.get("error"), result.get("traceback"))
    assert proc.returncode == 0, log[-3000:]
    case = json.loads((out / "case.json").read_text())
    job = swarf.Job.from_dict(case, name="freecad_job")
    own = swarf.rough(job, strategy="adaptive")
    return {
        "out": out,
        "result": result,
        "case": case,
        "job": job,
        "own": own,
        "posted": (out / "posted.ngc").read_text(),
        "fc_report": json.loads((out / "report.json").read_text()),
        "log": log,
    }


# ---- reading G-code ------------------------------------------------------------------------------

_WORD = re.compile(r"([A-Z])\s*([-+]?(?:\d+\.?\d*|\.\d+))")


def _motions(text):
    """The motions of a program: (G, x, y, z, i, j, feed) with modal positions and feed."""
    pos = {"X": None, "Y": None, "Z": None}
    mode, feed, out = None, None, []
    for raw in text.splitlines():
        line = re.sub(r"\([^)]*\)", " ", raw).split(";")[0].upper()
        words = _WORD.findall(line)
        gs = [int(float(v)) for k, v in words if k == "G" and float(v) in (0, 1, 2, 3)]
        if gs:
            mode = gs[-1]
        params = {k: float(v) for k, v in words if k in "XYZIJF"}
        if "F" in params:
            feed = params["F"]
        if not any(k in params for k in "XYZ"):
            continue
        pos.update({k: v for k, v in params.items() if k in pos})
        out.append((mode, pos["X"], pos["Y"], pos["Z"], params.get("I"), params.get("J"), None if mode == 0 else feed))
    return out


def _operation(posted):
    """The lines of the posted program between the operation's begin and finish comments."""
    lines = posted.splitlines()
    begin = [i for i, l in enumerate(lines) if l.strip() == "(begin operation: %s)" % OP_LABEL]
    end = [i for i, l in enumerate(lines) if l.strip() == "(finish operation: %s)" % OP_LABEL]
    assert len(begin) == 1 and len(end) == 1 and begin[0] < end[0], "no single %s operation posted" % OP_LABEL
    return "\n".join(lines[begin[0] + 1 : end[0]])


# ---- the interpreter ---------------------------------------------------------------------------


def _arc_length(start, end, centre, rotation):
    a0 = math.atan2(start[1] - centre[1], start[0] - centre[0])
    a1 = math.atan2(end[1] - centre[1], end[0] - centre[0])
    sweep = a1 - a0
    extra = (abs(rotation) - 1) * 2 * math.pi
    if rotation > 0:
        while sweep <= 0:
            sweep += 2 * math.pi
        sweep += extra
    else:
        while sweep >= 0:
            sweep -= 2 * math.pi
        sweep -= extra
    r0 = math.hypot(start[0] - centre[0], start[1] - centre[1])
    r1 = math.hypot(end[0] - centre[0], end[1] - centre[1])
    return math.hypot(0.5 * (r0 + r1) * abs(sweep), end[2] - start[2])


def _interpret(rs274, ngc, work):
    """Runs rs274 on the program in its own folder (its own HOME: rs274 maps $HOME/.tool.mmap);
    returns (feed length mm, straight feeds, arcs, traverses)."""
    work.mkdir()
    (work / "tool.tbl").write_text("".join("T%d P%d Z0 D0 ;zero-length tool\n" % (i, i) for i in range(1, 100)))
    env = dict(os.environ, HOME=str(work))
    proc = subprocess.run(
        [rs274, "-g", "-t", "tool.tbl", str(ngc), "canon.txt"],
        cwd=str(work),
        env=env,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        timeout=300,
    )
    # stderr always says "executing"; anything else is an error message
    err = [l.strip() for l in proc.stderr.decode("utf-8", "replace").splitlines() if l.strip() not in ("", "executing")]
    assert proc.returncode == 0 and not err, "rs274 on %s: exit %d: %s" % (ngc, proc.returncode, " | ".join(err))
    pos = [0.0, 0.0, 0.0]
    length, feeds, arcs, traverses = 0.0, 0, 0, 0
    for line in (work / "canon.txt").read_text().splitlines():
        m = re.search(r" (STRAIGHT_TRAVERSE|STRAIGHT_FEED|ARC_FEED|USE_LENGTH_UNITS|SELECT_PLANE)\((.*)\)", line)
        if not m:
            continue
        kind, args = m.group(1), [a.strip() for a in m.group(2).split(",")]
        if kind == "USE_LENGTH_UNITS":
            assert args[0] == "CANON_UNITS_MM", line
        elif kind == "SELECT_PLANE":
            assert args[0] == "CANON_PLANE_XY", line
        elif kind == "STRAIGHT_TRAVERSE":
            pos = [float(a) for a in args[:3]]
            traverses += 1
        elif kind == "STRAIGHT_FEED":
            to = [float(a) for a in args[:3]]
            length += math.dist(pos, to)
            pos, feeds = to, feeds + 1
        else:
            to = [float(args[0]), float(args[1]), float(args[5])]
            length += _arc_length(pos, to, (float(args[2]), float(args[3])), int(args[4]))
            pos, arcs = to, arcs + 1
    return length, feeds, arcs, traverses


# ---- the tests -----------------------------------------------------------------------------------


def test_gcode_commands_without_freecad():
    """The G-code reading of swarf.freecad (plain Python: runs without FreeCAD too)."""
    from swarf.freecad import gcode_commands

    program = """(swarf - post linuxcnc)
G21 G90 G17 G94 G40 G49 G80
G64 P0.01
T1 M6
G43 H1
S10000 M3
G0 Z5
(level 1 of 1: z -6.000)
G0 X9.52 Y1
G3 X5.02 Y19.289 Z0.632 I-2.25017 J0 F1000
G1 X4.869 Y19.436 F1400.5
X4.8
G0 Z5
M5
M2
"""
    assert gcode_commands(program) == [
        ("G0", {"Z": 5.0}),
        ("(level 1 of 1: z -6.000)", {}),
        ("G0", {"X": 9.52, "Y": 1.0}),
        ("G3", {"X": 5.02, "Y": 19.289, "Z": 0.632, "I": -2.25017, "J": 0.0, "F": 1000 / 60}),
        ("G1", {"X": 4.869, "Y": 19.436, "F": 1400.5 / 60}),
        ("G1", {"X": 4.8, "F": 1400.5 / 60}),
        ("G0", {"Z": 5.0}),
    ]
    assert [c for c, _ in gcode_commands(program, comments=False)].count("G0") == 3
    assert gcode_commands("G20\nG1 X1 F10\n") == [("G1", {"X": 25.4, "F": 254 / 60})]
    for bad in ("G91\nG1 X1", "G18\nG2 X1 Z1 I1 K0 F100", "G41 D1", "G1 X1 E5"):
        with pytest.raises(ValueError):
            gcode_commands(bad)



def _close(a, b, rel=0.01):
    return abs(a - b) <= rel * max(abs(a), abs(b))


def test_the_case_is_the_jobs_pocket(run):
    c = run["case"]
    assert c["units"] == "mm"
    assert (c["stock_top"], c["part_top"], c["floor"]) == (20.0, 20.0, 14.0)
    assert c["stock"] == [[0.0, 0.0], [100.0, 0.0], [100.0, 80.0], [0.0, 80.0]]
    assert c["tool"] == {"diameter": 6.0, "type": "flat", "number": 1}
    assert c["feed_default"] == pytest.approx(1000.0, abs=1e-6)
    assert c["spindle_rpm"] == 10000.0
    # the block's outline with the pocket as its one hole: 60 x 40 with 8 mm corners
    assert len(c["part"]) == 1 and len(c["part"][0]["holes"]) == 1
    hole = c["part"][0]["holes"][0]
    xs, ys = [p[0] for p in hole], [p[1] for p in hole]
    assert (min(xs), max(xs), min(ys), max(ys)) == pytest.approx((20, 80, 20, 60), abs=1e-6)
    area = 0.5 * abs(sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(hole, hole[1:] + hole[:1])))
    assert area == pytest.approx(60 * 40 - (4 - math.pi) * 8 * 8, abs=0.5)
    r = run["result"]
    assert r["op_in_job"] and r["op_tool_controller"] == "TC: 6 mm end mill"
    assert r["commands_after_reload"] == r["commands"]


def test_the_posted_program_has_arcs_and_lines(run):
    text = _operation(run["posted"])
    assert re.search(r"^G1 ", text, re.M), "no G1 in the posted operation"
    assert re.search(r"^G2 ", text, re.M) and re.search(r"^G3 ", text, re.M), "no G2/G3 arcs in the posted operation"
    assert "G64" not in run["posted"], "G64 belongs to the post's preamble, not the path"


def test_the_posted_moves_are_swarfs(run):
    swarf_moves = _motions(run["own"].gcode)
    posted_moves = _motions(_operation(run["posted"]))
    assert len(posted_moves) == len(swarf_moves), (len(posted_moves), len(swarf_moves))
    worst_xyz = worst_ij = worst_f = 0.0
    for k, (a, b) in enumerate(zip(swarf_moves, posted_moves)):
        assert a[0] == b[0], "move %d: G%s in swarf's program, G%s posted" % (k, a[0], b[0])
        for u, v in zip(a[1:4], b[1:4]):
            if u is not None and v is not None:
                worst_xyz = max(worst_xyz, abs(u - v))
        for u, v in zip(a[4:6], b[4:6]):
            assert (u is None) == (v is None), "move %d: %s posted as %s" % (k, a, b)
            if u is not None:
                worst_ij = max(worst_ij, abs(u - v))
        if a[6] is not None:
            worst_f = max(worst_f, abs(a[6] - b[6]))
    assert worst_xyz <= 0.001 + 1e-9, worst_xyz
    assert worst_ij <= 0.001 + 1e-9, worst_ij
    assert worst_f <= 0.001, "feeds differ by up to %g mm/min (F units)" % worst_f


def test_rs274_reads_the_posted_program(run, tmp_path):
    rs274 = _tool("rs274", "SWARF_REQUIRE_RS274", "LinuxCNC's G-code interpreter")
    length, feeds, arcs, _ = _interpret(rs274, run["out"] / "posted.ngc", tmp_path / "rs274")
    rep = run["own"].report
    assert arcs > 0 and feeds > 0
    assert _close(length, rep["cut_length_mm"], 0.005), (length, rep["cut_length_mm"])


def test_swarfs_figures_for_the_posted_program(run):
    own = run["own"].report
    fc = run["fc_report"]
    posted = swarf.check(run["job"], run["posted"])
    for name, r in (("FreeCAD's run", fc), ("the posted program", posted)):
        assert _close(r["time_min"], own["time_min"]), (name, r["time_min"], own["time_min"])
        assert _close(r["cut_length_mm"], own["cut_length_mm"]), (name, r["cut_length_mm"], own["cut_length_mm"])
        assert r["gouges"] == 0, (name, r["gouges"])
    assert own["gouges"] == 0


def test_a_pocket_round_an_island_in_freecads_default_stock(run_island, tmp_path):
    """FreeCAD's default stock is 1 mm bigger than the model on every side, top included: the
    case keeps the part up to the stock's top (that layer is not faced, and a warning says so),
    the pocket is cleared round the boss in levels of one tool diameter, and the posted program
    is swarf's own, with no gouge into the boss, the drafted pocket's leaning wall or the
    shallow pocket's rim."""
    r = run_island
    c = r["case"]
    assert (c["stock_top"], c["part_top"], c["floor"], c["stepdown"]) == (26.0, 26.0, 15.0, 6.0)
    assert c["stock"] == [[-1.0, -1.0], [121.0, -1.0], [121.0, 91.0], [-1.0, 91.0]]
    assert "are not faced by this operation" in r["log"]
    own = r["own"].report
    assert own["levels"] == [20.5, 15.0]
    assert own["gouges"] == 0 and own["rest_fraction"] < 0.001
    posted = swarf.check(r["job"], r["posted"])
    assert posted["gouges"] == 0 and posted["rapid_collisions"] == 0
    assert _close(posted["time_min"], own["time_min"]) and _close(posted["cut_length_mm"], own["cut_length_mm"])
    rs274 = _tool("rs274", "SWARF_REQUIRE_RS274", "LinuxCNC's G-code interpreter")
    length, _, arcs, _ = _interpret(rs274, r["out"] / "posted.ngc", tmp_path / "rs274")
    assert arcs > 0 and _close(length, own["cut_length_mm"], 0.005), (length, own["cut_length_mm"])
