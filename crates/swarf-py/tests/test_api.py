"""The Python API on the example jobs: the same programs and figures as the command line, the
exceptions, the arrays, the progress callback and the GIL released."""

import json
import subprocess
import threading
import time

import numpy as np
import pytest

import swarf
from conftest import CASES, EXAMPLES

#: The report's times of this run (they differ between any two runs).
TIMINGS = {"compute_s", "simulate_s", "total_s"}


def cli(swarf_bin, args, tmp_path):
    out = tmp_path / "cli.ngc"
    rep = tmp_path / "cli.json"
    subprocess.run([swarf_bin, "rough", *map(str, args), "-o", str(out), "--report", str(rep), "-q"], check=True)
    return out.read_text(), json.loads(rep.read_text())


def same_report(a, b):
    assert set(a) == set(b)
    diff = {k: (a[k], b[k]) for k in a if k not in TIMINGS and a[k] != b[k]}
    assert not diff


@pytest.mark.parametrize("case", CASES, ids=lambda p: p.stem)
def test_rough_is_the_command_lines(case, swarf_bin, tmp_path):
    gcode, report = cli(swarf_bin, [case], tmp_path)
    res = swarf.rough(swarf.load(case))
    assert res.gcode == gcode
    same_report(res.report, report)
    assert res.report["gouges"] == 0


def test_the_built_in_example_needs_no_file():
    job = swarf.example()
    assert (job.name, job.kind, job.tool_diameter) == ("demo_pocket", "2.5d", 6)
    res = swarf.rough(job)
    assert res.report["gouges"] == 0 and res.report["levels"] == [-3.0, -6.0]
    assert swarf.example(tool_diameter=8).tool_diameter == 8


def test_options_are_the_command_lines(swarf_bin, tmp_path):
    case = EXAMPLES / "cases/pocket_islands.json"
    flags = ["--strategy", "offset", "--tool-diameter", "8", "--engagement", "45", "--post", "grbl", "--conventional"]
    gcode, report = cli(swarf_bin, [case, *flags], tmp_path)
    res = swarf.rough(swarf.load(case), strategy="offset", tool_diameter=8, engagement=45, post="grbl", conventional=True)
    assert res.gcode == gcode
    same_report(res.report, report)
    # overrides given at load or at rough are the same job
    res2 = swarf.rough(swarf.load(case, tool_diameter=8, engagement=45), strategy="offset", post="grbl", conventional=True)
    assert res2.gcode == gcode


def test_a_3d_job_is_roughed_in_z_levels_as_the_command_line(swarf_bin, tmp_path):
    case = EXAMPLES / "3d/bowl_cavity.json"
    gcode, report = cli(swarf_bin, [case, "--stepdown", "8"], tmp_path)
    job = swarf.load(case, stepdown=8)
    assert job.kind == "3d"
    res = swarf.rough(job)
    assert res.gcode == gcode
    same_report(res.report, report)
    assert len(res.report["levels"]) > 1


def test_plan_tools_writes_the_command_lines_programs(swarf_bin, tmp_path):
    case = EXAMPLES / "3d/bowl_cavity.json"
    tools = EXAMPLES / "tools/table1.json"
    subprocess.run(
        [swarf_bin, "plan", str(case), "--tools", str(tools), "--output-dir", str(tmp_path / "cli"), "--no-simulate", "-q"],
        check=True,
    )
    plan = swarf.plan_tools(swarf.load(case), tools, simulate=False)
    assert plan.report["best"]["tools"] == json.loads((tmp_path / "cli/plan.json").read_text())["best"]["tools"]
    assert len(plan.programs) == len(plan.report["best"]["programs"]) >= 2
    for name, gcode, tp in plan.programs:
        assert gcode == (tmp_path / "cli" / name).read_text()
        assert tp.xyz.shape == (len(tp), 3)
    # the database as Python data gives the same plan
    again = swarf.plan_tools(swarf.load(case), json.loads(tools.read_text()), simulate=False)
    assert [g for _, g, _ in again.programs] == [g for _, g, _ in plan.programs]
    plan.write(tmp_path / "py")
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == sorted([n for n, _, _ in plan.programs] + ["plan.json"])


def test_a_case_from_python_data_is_the_files_job():
    case = EXAMPLES / "cases/pocket_islands.json"
    data = json.loads(case.read_text())
    # point lists as NumPy arrays
    data["stock"] = np.array(data["stock"], dtype=float)
    for poly in data["part"]:
        poly["outer"] = np.array(poly["outer"])
        poly["holes"] = [np.array(h) for h in poly["holes"]]
    job = swarf.Job.from_dict(data, name="pocket_islands")
    assert job.name == "pocket_islands" and job.kind == "2.5d"
    a = swarf.rough(job, simulate=False)
    b = swarf.rough(swarf.load(case), simulate=False)
    assert a.gcode == b.gcode


def test_a_mesh_from_python_data_is_the_stl_files_job():
    stl = EXAMPLES / "parts/bowl_cavity.stl"
    raw = stl.read_bytes()
    n = int(np.frombuffer(raw[80:84], "<u4")[0])
    rec = np.frombuffer(raw[84:], dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")], count=n)
    vertices = rec["v"].reshape(-1, 3).astype(np.float64)
    triangles = np.arange(3 * n).reshape(n, 3)
    job = swarf.Job.from_mesh(vertices, triangles, name="bowl_cavity", tool_diameter=10, stepdown=10)
    assert job.kind == "3d" and job.tool_diameter == 10
    a = swarf.rough(job, simulate=False)
    b = swarf.rough(swarf.load(stl, tool_diameter=10, stepdown=10), simulate=False)
    assert a.gcode == b.gcode
    # a box as 8 shared vertices and 12 triangles, from lists
    box = [[40.0 * (i & 1), 30.0 * (i >> 1 & 1), 10.0 * (i >> 2)] for i in range(8)]
    tris = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]]
    assert swarf.Job.from_mesh(box, tris, name="box", stock_above=2).summary.startswith("read STL part 40.0 × 30.0 × 10.0 mm")
    with pytest.raises(swarf.InputError) as e:
        swarf.Job.from_mesh(box, [[0, 1, 8]], name="box")
    assert (e.value.file, e.value.place) == ("box.stl", "triangles[0]")
    with pytest.raises(swarf.InputError, match="indices start at 0"):
        swarf.Job.from_mesh(box, [[0, 1, -1]], name="box")
    with pytest.raises(swarf.InputError) as e:
        swarf.Job.from_mesh([[0, 0, 0], [1, float("nan"), 0], [0, 1, 0]], [[0, 1, 2]])
    assert e.value.place == "vertices[1]"
    with pytest.raises(ValueError):
        swarf.Job.from_mesh([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]])


def test_arrays_have_their_shapes_and_types():
    res = swarf.rough(swarf.load(EXAMPLES / "cases/round_pocket.json"))
    tp = res.toolpath
    n = len(tp)
    assert n > 100
    assert (tp.xyz.shape, tp.xyz.dtype) == ((n, 3), np.float64)
    assert (tp.kind.shape, tp.kind.dtype) == ((n,), np.uint8)
    assert (tp.feed.shape, tp.feed.dtype) == ((n,), np.float64)
    assert (tp.arc.shape, tp.arc.dtype) == ((n,), np.int8)
    assert (tp.center.shape, tp.center.dtype) == ((n, 2), np.float64)
    assert tp.start.shape == (3,)
    assert np.array_equal(np.asarray(tp), tp.xyz)
    # rapids have no feed; arcs, and only arcs, have centres
    assert np.all(tp.feed[tp.kind == 0] == 0) and np.all(tp.feed[tp.kind != 0] > 0)
    assert np.array_equal(np.isnan(tp.center[:, 0]), tp.arc == 0) and np.any(tp.arc != 0)
    e = res.engagement
    assert e.dtype == np.float64 and e.ndim == 2 and e.shape[1] == len(swarf.ENGAGEMENT_COLUMNS) == 9
    col = {c: i for i, c in enumerate(swarf.ENGAGEMENT_COLUMNS)}
    assert np.all(np.diff(e[:, col["cut_length_mm"]]) >= 0)
    assert set(np.unique(e[:, col["kind"]])) <= {0.0, 1.0, 2.0}
    assert e[:, col["move"]].max() < n
    lateral = e[(e[:, col["kind"]] == 0) & (e[:, col["bore"]] == 0), col["tea_deg"]]
    assert lateral.max() == pytest.approx(res.report["engagement_deg"]["max"], abs=0.01)
    assert swarf.rough(swarf.load(EXAMPLES / "cases/round_pocket.json"), simulate=False).engagement is None


def test_bad_input_raises_errors_that_name_the_file_the_place_and_the_reason(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"tool": {"diameter": 6}, "stock": [[0,0],[10,0]], "floor": -1}')
    with pytest.raises(swarf.InputError) as e:
        swarf.load(bad)
    assert (e.value.file, e.value.place) == (str(bad), "stock")
    assert "at least 3" in e.value.reason
    assert isinstance(e.value, swarf.SwarfError)
    broken = tmp_path / "broken.json"
    broken.write_text('{"tool": {"diameter": 6},\n "stock": [[0,0],,]}')
    with pytest.raises(swarf.InputError) as e:
        swarf.load(broken)
    assert e.value.place.startswith("line 2 column")
    with pytest.raises(swarf.InputError, match="cannot read"):
        swarf.load(tmp_path / "missing.json")
    with pytest.raises(swarf.InputError) as e:
        swarf.Job.from_dict({"tool": {"diameter": 6}}, name="mine")
    assert (e.value.file, e.value.place) == ("mine.json", "stock")
    # a tool that fits nowhere is said of the file
    with pytest.raises(swarf.SwarfError, match="narrow_slot"):
        swarf.rough(swarf.load(EXAMPLES / "cases/narrow_slot.json"), tool_diameter=40)


def test_bad_settings_raise_setting_errors_and_unknown_keywords_type_errors():
    job = swarf.load(EXAMPLES / "cases/square_pocket.json")
    for kw, setting in [
        ({"strategy": "trochoidal"}, "strategy"),
        ({"post": "fanuc"}, "post"),
        ({"ramp_angle": 60}, "link.ramp_angle_deg"),
        ({"tool_diameter": -1}, "tool.diameter"),
        ({"engagement": 200}, "width.engagement_deg"),
        ({"res": 0}, "sim.res"),
        ({"res": 1e-300}, "sim.res"),  # (a grid whose cell count would overflow)
    ]:
        with pytest.raises(swarf.SettingError) as e:
            swarf.rough(job, **kw)
        assert e.value.setting == setting, kw
    with pytest.raises(TypeError, match="tool_diamter"):
        swarf.rough(job, tool_diamter=6)
    with pytest.raises(TypeError, match="strategy"):
        swarf.load(EXAMPLES / "cases/square_pocket.json", strategy="offset")
    with pytest.raises(TypeError):
        swarf.rough(job, feed="fast")


def test_outputs_are_atomic_and_never_replace_an_input(tmp_path):
    case = tmp_path / "pocket.json"
    case.write_text((EXAMPLES / "cases/l_pocket.json").read_text())
    res = swarf.rough(swarf.load(case))
    with pytest.raises(swarf.RefusedError) as e:
        res.write(tmp_path / "out.ngc", report=case)
    assert e.value.file == str(case)
    assert not (tmp_path / "out.ngc").exists()
    assert case.read_text() == (EXAMPLES / "cases/l_pocket.json").read_text()
    res.write(tmp_path / "out.ngc", report=tmp_path / "out.json")
    assert (tmp_path / "out.ngc").read_text() == res.gcode
    assert json.loads((tmp_path / "out.json").read_text())["time_min"] == res.report["time_min"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.json", "out.ngc", "pocket.json"]


def test_check_proves_a_program_read_from_g_code():
    job = swarf.load(EXAMPLES / "cases/pocket_islands.json")
    res = swarf.rough(job)
    rep = swarf.check(job, res.gcode)
    for k in ("time_min", "cut_length_mm", "gouges", "rapid_collisions"):
        assert rep[k] == pytest.approx(res.report[k], rel=1e-6), k
    assert rep["engagement_deg"]["max"] == pytest.approx(res.report["engagement_deg"]["max"], abs=0.5)
    with pytest.raises(swarf.InputError) as e:
        swarf.check(job, "G21 G90\nG18\nG1 X1 F100\n", name="other.ngc")
    assert e.value.file == "other.ngc" and e.value.place.startswith("line 2")


def test_progress_reaches_the_callback_and_its_errors_the_caller():
    job = swarf.load(EXAMPLES / "cases/square_pocket.json")
    seen = []
    swarf.rough(job, progress=lambda stage, f: seen.append((stage, f)))
    stages = [s for s, _ in seen]
    assert stages[0] == "plan" and "simulate" in stages
    for stage in ("plan", "simulate"):
        fs = [f for s, f in seen if s == stage]
        assert fs == sorted(fs) and fs[-1] == 1.0 and len(fs) >= 3
    assert len(seen) <= 250  # (at most every 1 % of a stage)

    def boom(stage, f):
        raise KeyError("stop")

    with pytest.raises(KeyError, match="stop"):
        swarf.rough(job, progress=boom)
    with pytest.raises(TypeError, match="progress"):
        swarf.rough(job, progress=5)


def test_the_gil_is_released_two_threads_plan_at_once():
    """Two jobs roughed in two threads overlap (each call's work spans its first to its last
    progress report) and take less time than one after the other (best of two tries: with the
    GIL held they would take as long); a Python thread counting beside a run keeps counting."""
    job = swarf.load(EXAMPLES / "cases/pocket_islands.json")
    spans = {}

    def work(i):
        marks = []
        swarf.rough(job, progress=lambda s, f: marks.append(time.perf_counter()))
        spans[i] = (marks[0], marks[-1])

    ratios = []
    for _ in range(2):
        t0 = time.perf_counter()
        work("a")
        work("b")
        one_by_one = time.perf_counter() - t0
        threads = [threading.Thread(target=work, args=(i,)) for i in (0, 1)]
        t0 = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        both = time.perf_counter() - t0
        (a0, a1), (b0, b1) = spans[0], spans[1]
        assert max(a0, b0) < min(a1, b1), "the two runs did not overlap"
        ratios.append(both / one_by_one)
        print(f"two jobs one after the other {one_by_one:.2f} s, in two threads {both:.2f} s ({one_by_one / both:.2f}x)")
    assert min(ratios) < 0.95, ratios

    runner = threading.Thread(target=work, args=("c",))
    count = 0
    runner.start()
    while runner.is_alive():
        count += 1
    print(f"a Python thread counted to {count} during a run")
    assert count > 10000, "the main thread was held up while swarf worked"


def test_the_stubs_name_what_the_module_has():
    """Every public name of the extension module is in its stub file, and the other way round."""
    import ast
    import pathlib

    stub = pathlib.Path(swarf.__file__).parent / "_swarf.pyi"
    tree = ast.parse(stub.read_text())
    named = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            named.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            named.add(node.target.id)
    public = {n for n in dir(swarf._swarf) if not n.startswith("_")}
    assert public == named, (public - named, named - public)
    assert (pathlib.Path(swarf.__file__).parent / "py.typed").exists()
