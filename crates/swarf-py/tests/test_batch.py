"""Batches on Dask: 20 jobs on a 2-worker LocalCluster give the same files as one process, and a
worker killed mid-batch costs only its tasks, which run again; every job's result comes back
once. The `swarf-batch` command on a folder, through a scheduler's address."""

import os
import signal
import time

import pytest

import swarf
from conftest import CASES

distributed = pytest.importorskip("distributed")
from swarf import cluster  # noqa: E402


def twenty_jobs():
    """The example cases, each at three tool diameters: 20 jobs of a second or less each."""
    jobs = []
    for case in CASES:
        for d in (5, 6, 8):
            jobs.append({"input": case, "name": f"{case.stem}_D{d}", "tool_diameter": d})
    return jobs[:20]


def files_of(folder):
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def local_cluster():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as lc:
        with distributed.Client(lc) as client:
            yield lc, client


def test_a_batch_is_byte_identical_to_one_process_and_survives_a_killed_worker(local_cluster, tmp_path):
    lc, client = local_cluster
    jobs = twenty_jobs()
    t0 = time.perf_counter()
    seq = list(cluster.run(jobs, tmp_path / "seq"))
    t_seq = time.perf_counter() - t0
    assert [r.get("error") for r in seq] == [None] * 20

    pids = set(client.run(os.getpid).values())
    assert len(pids) == 2
    results = []
    killed = None
    t0 = time.perf_counter()
    for r in swarf.batch(jobs, tmp_path / "par", client=client):
        results.append(r)
        if killed is None:
            # the other worker is busy with a job of its own: kill it there
            killed = next(p for p in pids if p != r["pid"])
            os.kill(killed, signal.SIGKILL)
    t_par = time.perf_counter() - t0
    print(f"20 jobs: one process {t_seq:.1f} s, 2 workers with one killed {t_par:.1f} s")

    names = [r["name"] for r in results]
    assert sorted(names) == sorted(j["name"] for j in jobs), "a result lost or given twice"
    assert all("error" not in r for r in results)
    # the killed worker's jobs ran again elsewhere (the nanny starts a new worker process)
    after = set(client.run(os.getpid).values())
    assert killed not in after
    assert files_of(tmp_path / "par") == files_of(tmp_path / "seq")
    assert len(files_of(tmp_path / "par")) == 40
    by_name = {r["name"]: r for r in seq}
    for r in results:
        assert r["sha256"] == by_name[r["name"]]["sha256"]


def test_a_failing_job_is_a_result_not_the_end_of_the_batch(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"tool": {"diameter": 6}}')
    res = {r["name"]: r for r in cluster.run([bad, CASES[0]], tmp_path / "out")}
    assert res["bad"]["error_type"] == "InputError" and "stock" in res["bad"]["error"]
    assert "error" not in res[CASES[0].stem]
    with pytest.raises(ValueError, match="two jobs named"):
        list(cluster.run([CASES[0], CASES[0]], tmp_path / "out"))


def test_swarf_batch_runs_a_folder_through_a_scheduler(local_cluster, tmp_path, capsys):
    lc, _ = local_cluster
    folder = tmp_path / "jobs"
    folder.mkdir()
    for case in CASES[:3]:
        (folder / case.name).write_bytes(case.read_bytes())
    assert cluster.main([str(folder), "--scheduler", lc.scheduler_address, "--tool-diameter", "5"]) == 0
    out = capsys.readouterr().out
    assert "3 of 3 jobs written" in out
    written = sorted(p.name for p in (folder / "swarf-out").iterdir())
    assert written == sorted(f"{c.stem}{s}" for c in CASES[:3] for s in (".ngc", ".report.json"))
    # the same folder again: the outputs are not picked up as jobs, and are the same bytes
    before = files_of(folder / "swarf-out")
    assert cluster.main([str(folder), "--scheduler", lc.scheduler_address, "--tool-diameter", "5", "-q"]) == 0
    assert files_of(folder / "swarf-out") == before
    # the command is installed with the package
    from importlib.metadata import entry_points

    eps = entry_points()
    scripts = eps.select(group="console_scripts") if hasattr(eps, "select") else eps.get("console_scripts", [])
    assert any(e.name == "swarf-batch" and e.value == "swarf.cluster:main" for e in scripts)
    # a folder with no job files
    empty = tmp_path / "empty"
    empty.mkdir()
    assert cluster.main([str(empty), "-q"]) == 2
