#!/usr/bin/python3
"""Batch throughput (issue 14, Speed): python3 -m curvflow.batch over the 20
shared meshes on a LocalCluster with 1 and then 2 workers, alternating,
each run into a fresh folder (nothing skipped). TSV on stdout, nothing
asserted.

    BUILD_DIR=build /usr/bin/python3 bench/bench_batch_throughput.py [--method M] [--steps N]
        [--rounds R] [--param KEY=VALUE]... [MANIFEST]

Columns: method, workers, round, meshes, ok, seconds of the job phase (first
submission to last result; the cluster's start is reported apart), meshes
per minute, cluster start seconds, load average of the machine at the
start (other work on the machine lowers the figures).
"""
import argparse
import csv
import os
import pathlib
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
BUILD = pathlib.Path(os.environ.get("BUILD_DIR") or ROOT / "build").resolve()
os.environ.setdefault("CURVFLOW_LIB_DIR", str(BUILD))
os.environ.setdefault("OMP_THREAD_LIMIT", "1")
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT / "python"), os.environ.get("PYTHONPATH")]))

from curvflow import batch  # noqa: E402


def main():
    p = argparse.ArgumentParser()
    p.add_argument("manifest", nargs="?")
    p.add_argument("--method", default="conformal-mcf")
    p.add_argument("--steps", type=int, default=10)
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--param", action="append", default=[])
    p.add_argument("--job-threads", type=int, default=1, help="BLAS threads per job [1, the batch's default]")
    a = p.parse_args()
    shared = os.environ.get("CURVFLOW_SHARED_DIR")
    manifest = pathlib.Path(a.manifest) if a.manifest else (
        (pathlib.Path(shared) if shared else ROOT.parent / "shared") / "meshes" / "MANIFEST.tsv")
    if not manifest.is_file():
        print("skip: %s not found" % manifest, file=sys.stderr)
        return 0
    params = dict(item.split("=", 1) for item in a.param)
    from distributed import Client, LocalCluster
    print("method\tworkers\tround\tmeshes\tok\tseconds\tmeshes_per_min\tcluster_start_s\tload_avg")
    for rnd in range(1, a.rounds + 1):
        for workers in (1, 2):
            load = os.getloadavg()[0]
            t = time.perf_counter()
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                   dashboard_address="127.0.0.1:0")
            client = Client(cluster)
            start = time.perf_counter() - t
            try:
                with tempfile.TemporaryDirectory() as out:
                    t = time.perf_counter()
                    recs = batch.run_batch(manifest, a.method, out, a.steps, None, params, "ply", client=client,
                                           job_threads=a.job_threads)
                    secs = time.perf_counter() - t
                    with open(os.path.join(out, "summary.csv")) as fp:
                        failed = [r["mesh"] + ":" + r["status"] for r in csv.DictReader(fp) if r["status"] != "ok"]
            finally:
                client.close()
                cluster.close()
            ok = sum(r.get("status") == "ok" for r in recs)
            print("%s\t%d\t%d\t%d\t%d\t%.1f\t%.1f\t%.1f\t%.1f" % (a.method, workers, rnd, len(recs), ok, secs,
                                                                  60 * len(recs) / secs, start, load), flush=True)
            if failed:
                print("# not ok: " + ", ".join(failed), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
