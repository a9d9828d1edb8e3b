"""One batch job: one mesh, in its own process (python3 -m curvflow._job SPEC_JSON).

Run by curvflow.batch on a Dask worker through subprocess, so that a crash,
hang or runaway memory use of one mesh ends only this process. Reads the
mesh, runs the flow, writes (atomically, with the library's writers) the
result mesh or, on a numerical failure or cancellation (SIGINT, which the
batch sends on a timeout), the last good state, and the JSONL log; prints
one JSON object (the result) as its last line on stdout.

Fault injection for the tests: CURVFLOW_BATCH_FAULT="crash:NAME" makes the
job of mesh NAME kill itself with SIGSEGV after loading (as a crash inside
the library would), "hang:NAME" makes it sleep (for --timeout).
"""
import json
import math
import os
import signal
import sys
import time

# vertex normals describe the input's shape, not the result's
_NORMALS = {"nx", "ny", "nz", "normal_x", "normal_y", "normal_z"}


def _fault(name):
    spec = os.environ.get("CURVFLOW_BATCH_FAULT", "")
    for item in filter(None, spec.split(",")):
        kind, _, target = item.partition(":")
        if target == name:
            return kind
    return None


def _closed_willmore(V, F):
    """W/4pi of a valid closed mesh, else None (as `curvflow info`)."""
    import curvflow
    try:
        i = curvflow.info(V, F)
    except curvflow.CurvflowError:
        return None
    return i.get("willmore_over_4pi")


def _materials(extras, input_path, out_dir, fmt):
    """An OBJ input's materials for an OBJ output, as the CLI's flow carries
    them: a relative `mtllib` made absolute (it names a file beside the
    input) unless the output goes to the input's directory. Other output
    formats have no place for them."""
    if fmt != "obj" or not (extras.get("material_libraries") or extras.get("material_names")):
        return {}
    in_dir = os.path.dirname(os.path.realpath(input_path))
    same = in_dir == os.path.realpath(out_dir)
    libs = [lib if same or os.path.isabs(lib) else os.path.join(in_dir, lib)
            for lib in extras["material_libraries"]]
    return {"material_libraries": libs, "material_names": extras["material_names"],
            "face_materials": extras["face_materials"]}


def run(spec):
    import curvflow
    t0 = time.perf_counter()
    name, out_dir, fmt = spec["name"], spec["out_dir"], spec["format"]
    res = {"mesh": name, "input": spec["input"], "status": "ok", "message": "", "steps": 0, "converged": None,
           "energy_before": None, "energy_after": None, "willmore_over_4pi_before": None,
           "willmore_over_4pi_after": None, "q_mean": None, "q_max": None, "output": None, "last_good": None,
           "log": None, "flow_seconds": None}
    try:
        V, F, extras = curvflow.load(spec["input"])
    except curvflow.MeshIOError as e:
        res.update(status="unreadable", message=str(e))
        return res
    except curvflow.InvalidMeshError as e:
        res.update(status="invalid-mesh", message=str(e))
        return res
    fault = _fault(name)
    if fault == "crash":
        os.kill(os.getpid(), signal.SIGSEGV)
    elif fault == "hang":
        while True:
            time.sleep(1)
    res["willmore_over_4pi_before"] = _closed_willmore(V, F)
    t1 = time.perf_counter()
    state = log = None
    try:
        state, log = curvflow.flow(V, F, spec["method"], steps=spec["steps"], time_step=spec["time_step"],
                                   **spec["params"])
    except KeyboardInterrupt as e:
        state, log = getattr(e, "last_positions", None), getattr(e, "log", None)
        res.update(status="cancelled", message=str(e))
    except curvflow.NumericalError as e:
        state, log = e.last_positions, e.log
        res.update(status="numerical-failure", message=str(e))
    except curvflow.InvalidMeshError as e:  # e.g. genus the method refuses
        res.update(status="invalid-mesh", message=str(e))
    except curvflow.CurvflowError as e:
        state, log = e.last_positions, e.log
        res.update(status="error", message="%s: %s" % (e.status or type(e).__name__, e))
    res["flow_seconds"] = time.perf_counter() - t1
    if log:
        res["steps"] = log[-1]["iteration"]
        res["energy_before"], res["energy_after"] = log[0]["energy"], log[-1]["energy"]
        res["log"] = os.path.join(out_dir, name + ".log.jsonl")
        curvflow.write_log(res["log"], log)
    if state is not None:
        path = os.path.join(out_dir, name + ("." if res["status"] == "ok" else ".last_good.") + fmt)
        # the input's properties (a PLY's colours, quality, labels) ride along, as with the CLI's
        # flow, where the output format and the names allow
        keep = {}
        for where in ("vertex_fields", "face_fields"):
            keep[where] = {k: v for k, v in (extras.get(where) or {}).items()
                           if fmt != "off" and k not in _NORMALS
                           and curvflow._lib.lib().cf_field_name_valid(k.encode())}
        curvflow.save(path, state, F, uv=extras["uv"], uv_faces=extras["uv_faces"], **keep,
                      **_materials(extras, spec["input"], out_dir, fmt))
        res["output" if res["status"] == "ok" else "last_good"] = path
        res["willmore_over_4pi_after"] = _closed_willmore(state, F)
        try:
            c = curvflow.compare(V, state, F)
            q = c["quasi_conformal_error"]
            res["q_mean"], res["q_max"] = q["mean"], q["max"]
        except curvflow.CurvflowError:
            pass  # a degenerated last state: no Q
    res["job_seconds"] = time.perf_counter() - t0
    return res


def _clean(v):
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def main():
    spec = json.loads(sys.argv[1])
    res = run(spec)
    print(json.dumps({k: _clean(v) for k, v in res.items()}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
