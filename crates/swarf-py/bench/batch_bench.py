"""A batch of jobs three ways: one process, a LocalCluster of 1 worker, one of 2 workers.

    python crates/swarf-py/bench/batch_bench.py [--jobs 100] [--workers 1,2] [--out DIR]

The jobs are the repository's example cases (examples/cases) at several tool diameters and
widths of cut, as a shop's order might vary them. Each way writes its programs and reports to
its own folder; the script checks that the three folders hold the same bytes, and prints a
table: wall time, jobs per minute, the speed-up over one process, and what a night of 10 000
such jobs would take on N machines like this one.

Needs swarf installed with its batch extra: pip install "./crates/swarf-py[batch]".
"""

import argparse
import filecmp
import os
import pathlib
import statistics
import sys
import tempfile
import time

import swarf
from swarf import cluster

ROOT = pathlib.Path(__file__).resolve().parents[3]


def jobs(n):
    cases = sorted((ROOT / "examples/cases").glob("*.json"))
    out = []
    for d in (4, 5, 6, 8):
        for e in (40, 50, 60, 70):
            for c in cases:
                out.append({"input": str(c), "name": f"{c.stem}_D{d}_E{e}", "tool_diameter": d, "engagement": e})
    if n > len(out):
        sys.exit(f"at most {len(out)} jobs")
    return out[:n]


def same(a, b):
    names = sorted(os.listdir(a))
    if names != sorted(os.listdir(b)):
        return False
    _, mismatch, errors = filecmp.cmpfiles(a, b, names, shallow=False)
    return not mismatch and not errors


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--jobs", type=int, default=100)
    ap.add_argument("--workers", default="1,2", help="worker counts of the local clusters, comma-separated")
    ap.add_argument("--out", help="where the outputs go (a temporary folder by default)")
    a = ap.parse_args()
    js = jobs(a.jobs)
    base = pathlib.Path(a.out or tempfile.mkdtemp(prefix="swarf-batch-bench-"))
    print(f"swarf {swarf.__version__}, {len(js)} jobs, {os.cpu_count()} CPUs, outputs under {base}")

    rows = []
    t0 = time.perf_counter()
    seq = list(cluster.run(js, base / "one_process"))
    t_seq = time.perf_counter() - t0
    failed = [r for r in seq if "error" in r]
    if failed:
        sys.exit(f"{len(failed)} jobs failed, e.g. {failed[0]['name']}: {failed[0]['error']}")
    per_job = [r["timings"]["total_s"] for r in seq]
    rows.append(("one process", t_seq, True))
    for w in [int(x) for x in a.workers.split(",") if x]:
        out = base / f"workers_{w}"
        t0 = time.perf_counter()
        res = list(swarf.batch(js, out, n_workers=w))
        t = time.perf_counter() - t0
        assert sorted(r["name"] for r in res) == sorted(j["name"] for j in js)
        rows.append((f"LocalCluster, {w} worker{'s' if w > 1 else ''}", t, same(base / "one_process", out)))

    print()
    print("| run | wall s | jobs/min | vs one process | outputs identical |")
    print("|---|---|---|---|---|")
    for name, t, ok in rows:
        print(f"| {name} | {t:.1f} | {60 * len(js) / t:.0f} | {t_seq / t:.2f}x | {'yes' if ok else 'NO'} |")
    mean = statistics.mean(per_job)
    print()
    print(
        f"a job's own time (swarf's total_s, one process): mean {mean:.2f} s, median "
        f"{statistics.median(per_job):.2f} s, max {max(per_job):.2f} s; total {sum(per_job):.1f} s of {t_seq:.1f} s wall"
    )
    best = min(rows[1:], key=lambda r: r[1]) if len(rows) > 1 else rows[0]
    rate = len(js) / best[1]  # jobs per second on this machine
    print(f"a night of 10 000 such jobs at this machine's best rate ({best[0]}, {rate * 60:.0f} jobs/min):")
    for n in (1, 4, 16, 64):
        print(f"  {n:>3} machine{'s' if n > 1 else ' '}: {10000 / (rate * n) / 3600:.2f} h")


if __name__ == "__main__":
    main()
