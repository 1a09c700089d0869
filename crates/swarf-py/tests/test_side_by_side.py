"""The benchmark script `scripts/side_by_side.py` against FreeCAD: its table row for one case,
and FreeCAD's program it writes (by FreeCAD's own `PathAdaptive.GenerateGCode`, run by
`freecadcmd`), proven again by the package.

Skipped without `freecadcmd` on PATH unless `SWARF_REQUIRE_FREECAD=1`.
"""

import os
import shutil
import subprocess
import sys

import pytest

from conftest import EXAMPLES, ROOT

import swarf


def test_the_table_gives_freecads_program_as_freecad_makes_it(swarf_bin, tmp_path):
    if shutil.which("freecadcmd") is None:
        if os.environ.get("SWARF_REQUIRE_FREECAD") == "1":
            pytest.fail("SWARF_REQUIRE_FREECAD=1 but no freecadcmd on PATH")
        pytest.skip("no freecadcmd (Debian: apt-get install freecad-python3)")
    case = EXAMPLES / "cases" / "round_pocket.json"
    out = subprocess.run(
        [
            sys.executable,
            str(ROOT / "scripts" / "side_by_side.py"),
            "--repeat",
            "1",
            "--swarf",
            swarf_bin,
            "--keep",
            str(tmp_path),
            str(case),
        ],
        check=True,
        capture_output=True,
        text=True,
        timeout=600,
    )
    head, rule, row = out.stdout.strip().splitlines()
    names = [c.strip() for c in head.strip("|").split("|")]
    cells = dict(zip(names, (c.strip() for c in row.strip("|").split("|"))))
    assert len(names) == 17 and cells["case"] == "round_pocket", out.stdout
    fc_min = float(cells["FreeCAD min"])
    swarf_min = float(cells["swarf min"])
    assert abs(float(cells["min / FreeCAD"]) - swarf_min / fc_min) < 0.01
    own_max, fc_max = (float(v) for v in cells["engagement max swarf / FreeCAD"].split(" / "))
    assert own_max == pytest.approx(float(cells["max engagement (ref)"].split()[0]), abs=1.0)
    assert 30.0 < fc_max < 120.0, "FreeCAD's helix bottom read outside its bore? %s" % row
    own_gouges, fc_gouges = (int(v) for v in cells["gouges swarf / FreeCAD"].split(" / "))
    assert own_gouges == 0
    # FreeCAD's program, kept: a helix from the stock top, then the adaptive paths at the level
    program = (tmp_path / "round_pocket.freecad.ngc").read_text()
    assert program.startswith("G21 G90 G17") and program.rstrip().endswith("M2")
    assert sum(1 for line in program.splitlines() if line.startswith("G1")) > 500
    # proven by the package on the same job: the table's figures
    rep = swarf.check(swarf.load(str(case)), program)
    assert rep["time_min"] == pytest.approx(fc_min, abs=0.006)
    assert rep["gouges"] == fc_gouges
    assert rep["engagement_deg"]["max"] == pytest.approx(fc_max, abs=0.6)
