#!/usr/bin/python3
"""Python overhead against the CLI (issue 14, Speed): a 10-step spin-willmore
flow on spot_3k, measured in one run, repetitions interleaved. TSV on
stdout, nothing asserted.

    BUILD_DIR=build /usr/bin/python3 bench/bench_python_overhead.py [MESH] [--reps N] [--steps N]

Rows (wall-clock median and minimum, and CPU-time median (user + system, all
threads; less sensitive to other load on the machine), in milliseconds):
  cli_process       `curvflow flow MESH -o OUT --method spin-willmore --steps N -q`,
                    wall time of the whole process (start, load, flow, write, exit)
  py_load_flow_save curvflow.load + curvflow.flow + curvflow.save in this process
                    (the same work as the CLI, without interpreter start-up)
  py_flow           curvflow.flow alone (arrays in, arrays out)
  raw_ctypes_flow   the same library calls made directly through ctypes with
                    nothing around them (mesh, options, flow create, run, copy)
  py_wrapper        py_flow - raw_ctypes_flow: what the package adds per call
                    (array checks, per-step log dicts, the SIGINT guard)
  py_import         `python3 -c "import curvflow, numpy"` process, once per
                    interpreter, not per call
  tiny_*            py_flow, raw_ctypes_flow and their difference on a 42-vertex
                    icosphere (20 x the repetitions): the wrapper's cost, which
                    does not grow with the mesh, measured where the library's
                    time does not bury it
and the overheads as percentages of cli_process.
"""
import ctypes
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
BUILD = pathlib.Path(os.environ.get("BUILD_DIR") or ROOT / "build").resolve()
os.environ.setdefault("CURVFLOW_LIB_DIR", str(BUILD))
os.environ.setdefault("OMP_THREAD_LIMIT", "1")

import curvflow  # noqa: E402
from curvflow import _lib  # noqa: E402


def raw_flow(L, V, F, steps):
    """The library calls of a flow with nothing around them."""
    ctx = ctypes.c_void_p()
    L.cf_context_create(ctypes.byref(ctx))
    d = _lib.MeshDesc(V.shape[0], V.ctypes.data, F.shape[0], F.ctypes.data, 0, None, None)
    mesh = ctypes.c_void_p()
    assert L.cf_mesh_create(ctx, ctypes.byref(d), ctypes.byref(mesh)) == 0
    opts = _lib.FlowOptions()
    kind = ctypes.c_int()
    L.cf_flow_kind_from_name(b"spin-willmore", ctypes.byref(kind))
    L.cf_flow_options_default(kind.value, ctypes.byref(opts))
    fl = ctypes.c_void_p()
    assert L.cf_flow_create(ctx, mesh, None, ctypes.byref(opts), ctypes.byref(fl)) == 0
    info = _lib.FlowInfo()
    assert L.cf_flow_run(fl, steps, ctypes.byref(info)) == 0
    import numpy as np
    out = np.ctypeslib.as_array(L.cf_flow_positions(fl), shape=(3 * V.shape[0],)).copy()
    L.cf_flow_destroy(ctypes.byref(fl))
    L.cf_mesh_destroy(ctypes.byref(mesh))
    L.cf_context_destroy(ctypes.byref(ctx))
    return out


def run_process(args, env=None):
    """Wall and CPU seconds (user + system, all threads) of a child process."""
    t = time.perf_counter()
    proc = subprocess.Popen(args, env=env)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - t
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise SystemExit("%s: exit %d" % (" ".join(args), proc.returncode))
    return wall, usage.ru_utime + usage.ru_stime


def in_process(fn):
    """Wall and CPU seconds (this process, all threads) of fn()."""
    t, c = time.perf_counter(), time.process_time()
    result = fn()
    return (time.perf_counter() - t, time.process_time() - c), result


def main():
    args = sys.argv[1:]
    reps, steps = 15, 10
    for opt in ("--reps", "--steps"):
        if opt in args:
            i = args.index(opt)
            val = int(args[i + 1])
            del args[i:i + 2]
            if opt == "--reps":
                reps = val
            else:
                steps = val
    shared = os.environ.get("CURVFLOW_SHARED_DIR")
    mesh = pathlib.Path(args[0]) if args else (pathlib.Path(shared) / "meshes" if shared
                                               else ROOT.parent / "shared" / "meshes") / "spot_3k.obj"
    if not mesh.is_file():
        print("skip: %s not found" % mesh, file=sys.stderr)
        return 0
    cli = str(BUILD / "curvflow")
    L = _lib.lib()
    keys = ("cli_process", "py_load_flow_save", "py_flow", "raw_ctypes_flow", "py_import")
    wall = {k: [] for k in keys}
    cpu = {k: [] for k in keys}

    def record(key, pair):
        wall[key].append(pair[0])
        cpu[key].append(pair[1])

    with tempfile.TemporaryDirectory() as tmp:
        out_cli, out_py = os.path.join(tmp, "cli.obj"), os.path.join(tmp, "py.obj")
        V, F, _ = curvflow.load(mesh)
        curvflow.flow(V, F, "spin-willmore", steps=steps)  # warm-up (first-use set-up, page cache)

        def load_flow_save():
            V1, F1, _ = curvflow.load(mesh)
            V2, _ = curvflow.flow(V1, F1, "spin-willmore", steps=steps)
            curvflow.save(out_py, V2, F1)

        for _ in range(reps):
            record("cli_process", run_process([cli, "flow", str(mesh), "-o", out_cli, "--method", "spin-willmore",
                                               "--steps", str(steps), "-q"]))
            record("py_load_flow_save", in_process(load_flow_save)[0])
            record("py_flow", in_process(lambda: curvflow.flow(V, F, "spin-willmore", steps=steps))[0])
            pair, raw = in_process(lambda: raw_flow(L, V, F, steps))
            record("raw_ctypes_flow", pair)
            record("py_import", run_process([sys.executable, "-c", "import curvflow, numpy"],
                                            env=dict(os.environ, PYTHONPATH=str(ROOT / "python"))))
        same = curvflow.load(out_cli)[0].tobytes() == curvflow.load(out_py)[0].tobytes() == raw.tobytes()
        # The wrapper's own cost does not grow with the mesh (arrays are passed
        # without copies; the per-step work is one log dict): measured on a
        # 42-vertex icosphere, where the library's time is small and the
        # difference is not buried in other load on the machine.
        tiny = os.path.join(tmp, "tiny.obj")
        subprocess.run([cli, "generate", "icosphere", "--subdivisions", "1", "-o", tiny], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        Vt, Ft, _ = curvflow.load(tiny)
        tiny_py, tiny_raw = [], []
        for _ in range(20 * reps):
            tiny_py.append(in_process(lambda: curvflow.flow(Vt, Ft, "spin-willmore", steps=steps))[0][0])
            tiny_raw.append(in_process(lambda: raw_flow(L, Vt, Ft, steps))[0][0])
    rows = {}
    for k in keys:
        rows[k] = (statistics.median(wall[k]) * 1e3, min(wall[k]) * 1e3, statistics.median(cpu[k]) * 1e3)
    rows["py_wrapper"] = tuple(a - b for a, b in zip(rows["py_flow"], rows["raw_ctypes_flow"]))
    print("# %s, %d vertices, spin-willmore %d steps, %d repetitions, library %s, load average %.1f" % (
        mesh.name, len(V), steps, reps, curvflow.library_path(), os.getloadavg()[0]))
    print("metric\twall_median_ms\twall_min_ms\tcpu_median_ms")
    for k in keys[:4] + ("py_wrapper", "py_import"):
        print("%s\t%.2f\t%.2f\t%.2f" % ((k,) + rows[k]))
    tiny = (statistics.median(tiny_py) * 1e3, min(tiny_py) * 1e3, statistics.median(tiny_raw) * 1e3,
            min(tiny_raw) * 1e3)
    print("tiny_py_flow\t%.3f\t%.3f\t-" % tiny[:2])
    print("tiny_raw_ctypes_flow\t%.3f\t%.3f\t-" % tiny[2:])
    wrapper_ms = tiny[0] - tiny[2]
    print("tiny_py_wrapper\t%.3f\t%.3f\t-" % (wrapper_ms, tiny[1] - tiny[3]))
    cli_row = rows["cli_process"]
    print("tiny_py_wrapper_vs_cli_wall_median_percent\t%+.2f" % (100 * wrapper_ms / cli_row[0]))
    print("tiny_py_wrapper_vs_cli_wall_min_percent\t%+.2f" % (100 * (tiny[1] - tiny[3]) / cli_row[1]))
    for i, what in ((0, "wall_median"), (2, "cpu_median")):
        print("py_load_flow_save_vs_cli_%s_percent\t%+.1f" % (what, 100 * (rows["py_load_flow_save"][i] - cli_row[i])
                                                              / cli_row[i]))
        print("py_wrapper_vs_cli_%s_percent\t%+.2f" % (what, 100 * rows["py_wrapper"][i] / cli_row[i]))
    print("results_identical\t%s" % ("yes" if same else "NO"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
