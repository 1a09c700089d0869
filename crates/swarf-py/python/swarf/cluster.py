"""Batches of swarf jobs on a Dask cluster.

A shop's real workload is a batch: every part of an order against every tool, every candidate
setup. ``batch`` runs each job as one task on a ``dask.distributed`` cluster (a
``LocalCluster`` on this machine when no client is given) and yields the results as they
finish; ``run`` runs the same tasks one after the other in this process. Both write each job's
outputs the same way, so the files of a batch are byte-identical to those of ``run``:

- ``OUT/NAME.ngc``: the G-code;
- ``OUT/NAME.report.json``: the report, without its three timings (``compute_s``,
  ``simulate_s``, ``total_s``), which differ from run to run; they are in the result instead.

Each file is written atomically (a temporary beside it, renamed into place once whole), so a
worker that dies mid-write leaves no partial output (at most a hidden temporary,
``.NAME.ngc.swarf-tmp-PID``, which nothing reads). A worker that dies mid-batch costs only
the tasks it held: the scheduler runs them again on another worker, and each job's result is
yielded once. A job that fails (a bad file, a job that cannot be machined) is a result with
``error`` set, not the end of the batch.

    import swarf
    for r in swarf.batch(["a.json", "b.stl", {"input": "c.dxf", "tool_diameter": 3}], "out"):
        print(r["name"], r["time_min"], r.get("error"))

The command ``swarf-batch DIR --scheduler ADDRESS`` runs every job file in a folder.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from pathlib import Path
from typing import Any, Dict, Iterable, Iterator, List, Mapping, Optional, Union

#: The report's keys that are times of this run (left out of the written report).
TIMINGS = ("compute_s", "simulate_s", "total_s")
#: The job files ``swarf-batch`` picks up in a folder.
SUFFIXES = (".json", ".stl", ".dxf", ".svg")

JobSpec = Union[str, "os.PathLike[str]", Mapping[str, Any]]


def specs_of(jobs: Iterable[JobSpec], settings: Optional[Mapping[str, Any]] = None) -> List[Dict[str, Any]]:
    """The jobs as task specs: ``{"input": path, "name": stem, **keywords}``. A job is a path
    or a dict with ``input`` (a path), an optional ``name`` (the output's stem; the input's
    stem by default) and any of ``swarf.rough``'s keywords, which take precedence over
    ``settings`` (given to every job). Names must be unique (``ValueError``)."""
    specs: List[Dict[str, Any]] = []
    seen: Dict[str, str] = {}
    for j in jobs:
        spec = dict(settings or {})
        if isinstance(j, Mapping):
            spec.update(j)
        else:
            spec["input"] = j
        if "input" not in spec:
            raise ValueError(f"a job without an input: {j!r}")
        spec["input"] = os.fspath(spec["input"])
        name = spec.get("name") or Path(spec["input"]).stem
        spec["name"] = name
        if name in seen:
            raise ValueError(f"two jobs named {name!r} ({seen[name]} and {spec['input']}): give one a name")
        seen[name] = spec["input"]
        specs.append(spec)
    return specs


def run_one(spec: Mapping[str, Any], out_dir: str) -> Dict[str, Any]:
    """One job: read, roughed, proven, written to ``out_dir``. Returns a plain dict: ``name``,
    ``input``, ``gcode`` and ``report`` (the files written), ``sha256`` (of the G-code),
    ``time_min``, ``engagement_max_deg``, ``gouges``, ``rest_fraction``, the run's
    ``timings``, the worker's ``pid``; or ``error`` (and ``error_type``) when the job failed."""
    import swarf

    spec = dict(spec)
    name = spec.pop("name")
    path = spec.pop("input")
    result: Dict[str, Any] = {"name": name, "input": path, "pid": os.getpid()}
    try:
        job = swarf.load(path)
        res = swarf.rough(job, **spec)
        report = {k: v for k, v in res.report.items() if k not in TIMINGS}
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        gcode_path = out / f"{name}.ngc"
        report_path = out / f"{name}.report.json"
        swarf._swarf.write_files(
            [
                (os.fspath(gcode_path), res.gcode.encode()),
                (os.fspath(report_path), (json.dumps(report, indent=1, sort_keys=True) + "\n").encode()),
            ],
            [os.fspath(f) for f in job.files],
        )
        result.update(
            gcode=os.fspath(gcode_path),
            report=os.fspath(report_path),
            sha256=hashlib.sha256(res.gcode.encode()).hexdigest(),
            time_min=res.report.get("time_min"),
            engagement_max_deg=(res.report.get("engagement_deg") or {}).get("max"),
            gouges=res.report.get("gouges"),
            rest_fraction=res.report.get("rest_fraction"),
            timings={k: res.report.get(k) for k in TIMINGS},
        )
    except (swarf.SwarfError, OSError, ValueError, TypeError) as e:
        result.update(error=str(e), error_type=type(e).__name__)
    return result


def run(jobs: Iterable[JobSpec], out_dir: Union[str, "os.PathLike[str]"], **settings: Any) -> Iterator[Dict[str, Any]]:
    """The batch in this process, one job after the other (the reference ``batch`` is
    compared with)."""
    for spec in specs_of(jobs, settings):
        yield run_one(spec, os.fspath(out_dir))


def _key(spec: Mapping[str, Any]) -> str:
    blob = json.dumps(spec, sort_keys=True, default=str).encode()
    return f"swarf-{spec['name']}-{hashlib.sha256(blob).hexdigest()[:12]}"


def batch(
    jobs: Iterable[JobSpec],
    out_dir: Union[str, "os.PathLike[str]"],
    client: Any = None,
    n_workers: int = 2,
    **settings: Any,
) -> Iterator[Dict[str, Any]]:
    """Runs the jobs as tasks on a Dask cluster and yields each job's result (``run_one``'s
    dict) once, as it finishes. ``client`` is a ``distributed.Client``; without one a
    ``LocalCluster`` of ``n_workers`` single-threaded worker processes is started here and
    closed at the end. Keywords are ``swarf.rough``'s, for every job. The workers need swarf
    installed and ``out_dir`` on a file system they share with one another."""
    from distributed import Client, LocalCluster, as_completed

    specs = specs_of(jobs, settings)
    out = os.fspath(Path(out_dir).absolute())
    own = None
    if client is None:
        # (one thread per worker: swarf uses its own threads within a job)
        cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        own = (client, cluster)
    try:
        futures = [client.submit(run_one, s, out, key=_key(s), pure=False, retries=2) for s in specs]
        for f in as_completed(futures):
            yield f.result()
    finally:
        if own is not None:
            own[0].close()
            own[1].close()


def jobs_in(folder: Union[str, "os.PathLike[str]"]) -> List[Path]:
    """The job files in a folder (not its subfolders): cases, STL parts, drawings, by name."""
    return sorted(p for p in Path(folder).iterdir() if p.is_file() and p.suffix.lower() in SUFFIXES)


def main(argv: Optional[List[str]] = None) -> int:
    """``swarf-batch DIR [--scheduler ADDRESS] [--out OUT] [--workers N] [swarf rough options]``"""
    ap = argparse.ArgumentParser(
        prog="swarf-batch",
        description="Rough every job file in a folder (cases, STL parts, DXF and SVG drawings) on a Dask cluster.",
    )
    ap.add_argument("dir", help="the folder of job files")
    ap.add_argument("--scheduler", metavar="ADDRESS", help="a Dask scheduler (tcp://host:8786); a local cluster when not given")
    ap.add_argument("--out", metavar="DIR", help="where the programs and reports go (default: DIR/swarf-out)")
    ap.add_argument("--workers", type=int, default=2, metavar="N", help="workers of the local cluster (default 2)")
    ap.add_argument("--strategy", help="clearing strategy (adaptive by default)")
    ap.add_argument("--tool-diameter", type=float, metavar="MM")
    ap.add_argument("--engagement", type=float, metavar="DEG")
    ap.add_argument("--stepdown", type=float, metavar="MM")
    ap.add_argument("--post", help="controller dialect (linuxcnc, grbl)")
    ap.add_argument("-q", "--quiet", action="store_true", help="only the summary")
    a = ap.parse_args(argv)
    files = jobs_in(a.dir)
    if not files:
        print(f"swarf-batch: {a.dir}: no job files ({', '.join(SUFFIXES)})", file=sys.stderr)
        return 2
    out = a.out or os.path.join(a.dir, "swarf-out")
    settings = {
        k: v
        for k, v in {
            "strategy": a.strategy,
            "tool_diameter": a.tool_diameter,
            "engagement": a.engagement,
            "stepdown": a.stepdown,
            "post": a.post,
        }.items()
        if v is not None
    }
    client = None
    if a.scheduler:
        from distributed import Client

        client = Client(a.scheduler)
    t0 = time.perf_counter()
    failed = 0
    n = 0
    try:
        for r in batch(files, out, client=client, n_workers=a.workers, **settings):
            n += 1
            if "error" in r:
                failed += 1
                print(f"swarf-batch: {r['input']}: {r['error']}", file=sys.stderr)
            elif not a.quiet:
                print(
                    f"{r['name']}: {r['time_min']:.2f} min, engagement max {r['engagement_max_deg']:.1f} deg, "
                    f"{r['gouges']} gouges -> {r['gcode']}"
                )
    finally:
        if client is not None:
            client.close()
    print(f"swarf-batch: {n - failed} of {n} jobs written to {out} in {time.perf_counter() - t0:.1f} s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
