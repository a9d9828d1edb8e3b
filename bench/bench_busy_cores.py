#!/usr/bin/env python3
"""Whole-process time of `curvflow flow` while other processes keep the
cores busy, with the library's solver threads at the default
(CURVFLOW_THREADS unset: one thread in every factorisation and solve) and
at 0 (OpenBLAS as the process set it: one thread per core), alternated.

    python3 bench/bench_busy_cores.py [--curvflow PATH] [--busy 0,1,2] [--rounds 3]
        [--steps N] [--method NAME] MESH ...

For each mesh and each count of busy processes (busy loops started before
the runs and stopped after them), prints one TSV row per setting: the
median, smallest and largest wall seconds over the rounds, and the median
user and system seconds. Nothing is asserted (docs/linalg.md, "OpenBLAS's
threads"). Without MESH: the generated bumpy sphere of 2 562 vertices.
"""
import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time


def busy_loops(n):
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]


def run_once(cmd, env):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        sys.exit("%s: exit %d: %s" % (" ".join(cmd), proc.returncode, proc.stderr.strip()))
    return wall, after.ru_utime - before.ru_utime, after.ru_stime - before.ru_stime


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("meshes", nargs="*")
    p.add_argument("--curvflow", default=os.path.join(os.environ.get("BUILD_DIR", "build"), "curvflow"))
    p.add_argument("--busy", default="0,1,2", help="counts of busy processes, comma-separated [0,1,2]")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--steps", type=int, default=10)
    p.add_argument("--method", default="spin-willmore")
    a = p.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        meshes = a.meshes
        if not meshes:
            m = os.path.join(tmp, "bumpy.obj")
            subprocess.run([a.curvflow, "generate", "bumpy-sphere", "-o", m], check=True, stderr=subprocess.DEVNULL)
            meshes = [m]
        out = os.path.join(tmp, "out.obj")
        settings = [("default (1)", None), ("0 (OpenBLAS's own)", "0")]
        print("mesh\tbusy\tCURVFLOW_THREADS\twall_median_s\twall_min_s\twall_max_s\tuser_s\tsys_s")
        for mesh in meshes:
            cmd = [a.curvflow, "flow", mesh, "-o", out, "--method", a.method, "--steps", str(a.steps), "-q"]
            for busy in [int(b) for b in a.busy.split(",")]:
                loops = busy_loops(busy)
                try:
                    time.sleep(0.3)
                    rows = {name: [] for name, _ in settings}
                    for _ in range(a.rounds):
                        for name, value in settings:
                            env = dict(os.environ)
                            env.pop("CURVFLOW_THREADS", None)
                            if value is not None:
                                env["CURVFLOW_THREADS"] = value
                            rows[name].append(run_once(cmd, env))
                finally:
                    for lp in loops:
                        lp.kill()
                        lp.wait()
                for name, _ in settings:
                    walls = [r[0] for r in rows[name]]
                    print("%s\t%d\t%s\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f" % (
                        os.path.basename(mesh), busy, name, statistics.median(walls), min(walls), max(walls),
                        statistics.median(r[1] for r in rows[name]), statistics.median(r[2] for r in rows[name])))
                sys.stdout.flush()


if __name__ == "__main__":
    main()
