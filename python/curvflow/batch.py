"""Batch runs over data sets on Dask distributed (issue 14, item 3).

    python3 -m curvflow.batch MANIFEST.csv --method NAME --out DIR
        [--steps N] [--time-step T] [--param KEY=VALUE]... [--format obj|ply]
        [--scheduler ADDRESS | --workers N] [--timeout SECONDS] [--job-threads K]
        [--allow-missing] [--report]

One job per mesh. Each job is a separate process (python3 -m curvflow._job)
started by a Dask worker, so a crash, hang or timeout of one mesh is
recorded and the others go on. Without --scheduler a LocalCluster with
--workers workers runs on this machine; with it, any running Dask scheduler
(its workers need this package importable and DIR on a shared filesystem).

Manifest: CSV (or TSV: a tab in the header line) with a header naming the
mesh column `path` (or `file` / `mesh`); paths are relative to the
manifest's folder. Optional columns: `name` (output stem, default the file
stem), `steps` and `time_step` (per-mesh overrides). The shared
meshes' MANIFEST.tsv works as is.

Outputs in DIR, each written atomically (temporary file + rename):
  NAME.obj|ply            the result (texture coordinates kept)
  NAME.last_good.obj|ply  the last good state of a failed, cancelled or timed-out flow
  NAME.log.jsonl          the per-step log (the CLI's --log layout)
  NAME.json               the job's record, written last: a rerun skips a mesh whose
                          record says ok for the same request and whose result exists
  summary.csv             one row per mesh (SUMMARY_COLUMNS)
Statuses: ok, invalid-mesh, unreadable, missing, numerical-failure, error,
timeout, crashed, cancelled.

Exit status: 0 every mesh ok, 1 usage error (arguments, manifest, unknown
method or parameter), 2 the batch ran and some meshes failed (summary.csv
says which and why).
"""
import argparse
import csv
import io
import json
import os
import pathlib
import signal
import subprocess
import sys
import time

SUMMARY_COLUMNS = ["mesh", "status", "message", "steps", "energy_before", "energy_after",
                   "willmore_over_4pi_before", "willmore_over_4pi_after", "q_mean", "q_max", "seconds",
                   "output", "last_good", "log", "input", "worker", "skipped"]
_PATH_COLUMNS = ("path", "file", "mesh")
# SIGINT first (the flow cancels at the end of its current step and the
# job writes the last good state), SIGKILL after this grace period.
KILL_GRACE_SECONDS = 10.0


class ManifestError(ValueError):
    """The manifest cannot be used: unreadable, no path column, duplicate
    names, missing files."""


def read_manifest(path, allow_missing=False):
    """Rows of the manifest as dicts with input (absolute path), name, and
    optional steps / time_step overrides. Missing files raise ManifestError
    naming them, unless allow_missing (they are then marked missing=True)."""
    path = pathlib.Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise ManifestError("%s: cannot read the manifest (%s)" % (path, e.strerror or e)) from None
    lines = text.splitlines()
    if not lines:
        raise ManifestError("%s: empty manifest (expected a header with a 'path' column)" % path)
    delimiter = "\t" if "\t" in lines[0] else ","
    reader = csv.DictReader(io.StringIO(text), delimiter=delimiter)
    fields = [f.strip() for f in (reader.fieldnames or [])]
    column = next((c for c in _PATH_COLUMNS if c in fields), None)
    if column is None:
        raise ManifestError("%s: line 1: no mesh column (expected one of %s, got %s)"
                            % (path, ", ".join(_PATH_COLUMNS), ", ".join(fields) or "nothing"))
    base = path.resolve().parent
    rows, names, missing = [], {}, []
    for lineno, raw in enumerate(reader, start=2):
        row = {(k or "").strip(): (v or "").strip() for k, v in raw.items() if k is not None}
        if not row.get(column):
            continue  # blank line or no file
        mesh = pathlib.Path(row[column])
        full = mesh if mesh.is_absolute() else base / mesh
        # the default name is the file's stem with every character outside letters, digits and
        # "-_." made "_" ("scan 01 (left).obj" -> "scan_01__left_"); a given name must be plain
        name = row.get("name") or "".join(c if c.isalnum() or c in "-_." else "_" for c in mesh.stem)
        if name in names:
            raise ManifestError("%s: line %d: output name '%s' is already used on line %d (add a 'name' column)"
                                % (path, lineno, name, names[name]))
        if not name.replace("-", "").replace("_", "").replace(".", "").isalnum():
            raise ManifestError("%s: line %d: name '%s' is not a plain file stem (letters, digits, '-', '_' and "
                                "'.' only)" % (path, lineno, name))
        names[name] = lineno
        entry = {"input": str(full), "name": name, "line": lineno, "missing": not full.is_file()}
        for key, conv in (("steps", int), ("time_step", float)):
            if row.get(key):
                try:
                    entry[key] = conv(row[key])
                except ValueError:
                    raise ManifestError("%s: line %d: %s '%s' is not a number" % (path, lineno, key, row[key])) \
                        from None
        if entry["missing"]:
            missing.append("line %d: %s" % (lineno, full))
        rows.append(entry)
    if not rows:
        raise ManifestError("%s: no meshes listed" % path)
    if missing and not allow_missing:
        raise ManifestError("%s: %d mesh file%s missing (%s); fix the manifest or pass --allow-missing to "
                            "record them as missing" % (path, len(missing), "s are" if len(missing) > 1 else " is",
                                                        "; ".join(missing)))
    return rows


def _request(spec):
    """What makes a stored result reusable: same input, method, steps,
    parameters and format."""
    return {k: spec[k] for k in ("input", "method", "steps", "time_step", "params", "format")}


def complete_record(spec):
    """The stored record of a mesh if its result is complete for this
    request (status ok, same request, result file present), else None."""
    rec_path = os.path.join(spec["out_dir"], spec["name"] + ".json")
    try:
        with open(rec_path, encoding="utf-8") as fp:
            rec = json.load(fp)
    except (OSError, ValueError):
        return None
    if rec.get("status") != "ok" or rec.get("request") != _request(spec):
        return None
    if not rec.get("output") or not os.path.isfile(rec["output"]):
        return None
    return rec


def _package_parent():
    import curvflow
    return str(pathlib.Path(curvflow.__file__).resolve().parent.parent)


def run_job(spec):
    """Runs one mesh in a subprocess and writes its record (NAME.json).
    Executed on a Dask worker; never raises for a failure of the mesh."""
    import curvflow
    t0 = time.perf_counter()
    rec = {"mesh": spec["name"], "input": spec["input"], "request": _request(spec), "started_at": time.time()}
    try:
        import distributed
        rec["worker"] = distributed.get_worker().address
    except (ImportError, ValueError):
        rec["worker"] = "local"
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [_package_parent(), env.get("PYTHONPATH")]))
    threads = str(spec.get("job_threads") or 1)
    # CURVFLOW_THREADS: the library's own setting (cf_context_set_threads),
    # which would otherwise keep a job's solvers on one thread
    env.update(OPENBLAS_NUM_THREADS=threads, OMP_NUM_THREADS=threads, OMP_THREAD_LIMIT="1", CURVFLOW_THREADS=threads)
    try:
        lib_dir = os.path.dirname(curvflow.library_path())
        env.setdefault("CURVFLOW_LIB_DIR", lib_dir)
    except curvflow.CurvflowError:
        pass
    if spec.get("missing"):
        rec.update(status="missing", message="%s: no such file" % spec["input"])
    else:
        proc = subprocess.Popen([sys.executable, "-m", "curvflow._job", json.dumps(spec)], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, env=env)
        timed_out = False
        try:
            out, err = proc.communicate(timeout=spec.get("timeout"))
        except subprocess.TimeoutExpired:
            timed_out = True
            proc.send_signal(signal.SIGINT)
            try:
                out, err = proc.communicate(timeout=KILL_GRACE_SECONDS)
            except subprocess.TimeoutExpired:
                proc.kill()
                out, err = proc.communicate()
        result = None
        for line in reversed((out or "").strip().splitlines()):
            try:
                result = json.loads(line)
                break
            except ValueError:
                continue
        if result is not None:
            rec.update(result)
        tail = " | ".join((err or "").strip().splitlines()[-3:])
        if timed_out:
            rec["status"] = "timeout"
            rec["message"] = "no result after %g s (SIGINT sent%s)%s" % (
                spec["timeout"], "; the state reached is in last_good" if rec.get("last_good") else "",
                (": " + tail) if tail and not rec.get("last_good") else "")
        elif result is None:
            if proc.returncode < 0:
                sig = signal.Signals(-proc.returncode).name
                msg = "the job process died with %s" % sig
            else:
                msg = "the job process exited with status %d and no result" % proc.returncode
            rec.update(status="crashed", message=msg + ((": " + tail) if tail else ""))
    rec["seconds"] = time.perf_counter() - t0
    curvflow.write_text_atomic(os.path.join(spec["out_dir"], spec["name"] + ".json"),
                               json.dumps(rec, indent=1) + "\n")
    return rec


def _fmt(v):
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return str(v)


def write_summary(path, records):
    """summary.csv (atomically): one row per mesh in manifest order."""
    import curvflow
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(SUMMARY_COLUMNS)
    for rec in records:
        w.writerow([_fmt(rec.get(c)) for c in SUMMARY_COLUMNS])
    curvflow.write_text_atomic(path, buf.getvalue())


def _parse_args(argv):
    p = argparse.ArgumentParser(prog="python3 -m curvflow.batch", description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog="Statuses, outputs and exit codes: see docs/python.md.")
    p.add_argument("manifest", help="CSV/TSV with a path (or file, mesh) column; optional name, steps, time_step")
    p.add_argument("--method", required=True, help="flow method (python3 -c 'import curvflow; "
                   "print(list(curvflow.methods()))')")
    p.add_argument("--out", required=True, help="output folder (created)")
    p.add_argument("--steps", type=int, default=10, help="steps per mesh [10]")
    p.add_argument("--time-step", type=float, default=None, help="the method's scale-free time step")
    p.add_argument("--param", "-p", action="append", default=[], metavar="KEY=VALUE",
                   help="method parameter (repeatable), as curvflow flow --param")
    p.add_argument("--format", choices=("obj", "ply"), default="ply", help="result format [ply: binary, exact]")
    p.add_argument("--scheduler", default=None, help="address of a running Dask scheduler (default: LocalCluster)")
    p.add_argument("--workers", type=int, default=None, help="LocalCluster workers [number of cores]")
    p.add_argument("--timeout", type=float, default=None, help="seconds per mesh before it is cancelled (SIGINT, "
                   "then SIGKILL after %g s); default none" % KILL_GRACE_SECONDS)
    p.add_argument("--job-threads", type=int, default=None,
                   help="BLAS (OpenBLAS/OpenMP) threads per job [1: the workers run meshes in parallel]")
    p.add_argument("--allow-missing", action="store_true", help="record missing mesh files instead of refusing "
                   "the manifest")
    p.add_argument("--report", action="store_true", help="also write NAME.html per mesh with `curvflow report` "
                   "(when the tool has it)")
    p.add_argument("--quiet", "-q", action="store_true", help="no line per mesh")
    return p.parse_args(argv)


# distributed's Nanny writes these into the parent's os.environ when it
# starts workers (pre-spawn-environ) and leaves them there: every later
# subprocess of the caller (e.g. the CLI) would run with one BLAS thread,
# and a different BLAS thread count changes results in the last bits.
_NANNY_ENVIRON = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MALLOC_TRIM_THRESHOLD_")


def _local_cluster(n_workers):
    """A LocalCluster of n_workers single-threaded worker processes, leaving
    the caller's environment as it was."""
    from distributed import LocalCluster
    saved = {k: os.environ.get(k) for k in _NANNY_ENVIRON}
    try:
        return LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                            dashboard_address="127.0.0.1:0")
    finally:
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def run_batch(manifest, method, out, steps=10, time_step=None, params=None, fmt="ply", scheduler=None,
              workers=None, timeout=None, job_threads=None, allow_missing=False, report=False, quiet=True,
              client=None):
    """The batch as a function (what the command line calls). Returns the
    list of records in manifest order. client: an existing
    distributed.Client to use instead of creating one."""
    import curvflow
    params = dict(params or {})
    curvflow.check_params(method, time_step, **params)
    if timeout is not None and timeout <= 0:
        raise curvflow.UsageError("--timeout must be > 0, got %g" % timeout)
    if workers is not None and workers < 1:
        raise curvflow.UsageError("--workers must be >= 1, got %d" % workers)
    if steps < 0:
        raise curvflow.UsageError("--steps must be >= 0, got %d" % steps)
    rows = read_manifest(manifest, allow_missing)
    os.makedirs(out, exist_ok=True)
    out = str(pathlib.Path(out).resolve())
    n_workers = workers or os.cpu_count() or 1
    # Parallelism comes from the workers (one mesh each); BLAS threads inside
    # a job only fight the other jobs (armadillo_26k, spin-willmore on 2
    # cores under load: 3.4 s with one thread, 4.4-6.7 s with two).
    job_threads = job_threads or 1
    specs = []
    for r in rows:
        specs.append({"name": r["name"], "input": r["input"], "missing": r["missing"], "out_dir": out,
                      "method": method, "steps": r.get("steps", steps),
                      "time_step": r.get("time_step", time_step), "params": params, "format": fmt,
                      "timeout": timeout, "job_threads": job_threads})
    records = {}
    todo = []
    for s in specs:
        rec = complete_record(s)
        if rec is not None:
            rec["skipped"] = True
            records[s["name"]] = rec
        else:
            todo.append(s)
    if not quiet and len(todo) < len(specs):
        print("curvflow.batch: %d of %d meshes already complete in %s (skipped)" % (len(specs) - len(todo),
              len(specs), out), flush=True)
    elapsed = startup = 0.0
    if todo:
        from distributed import Client, as_completed
        t_start = time.perf_counter()
        cluster = own_client = None
        if client is None:
            if scheduler:
                client = own_client = Client(scheduler)
            else:
                cluster = _local_cluster(n_workers)
                client = own_client = Client(cluster)
        t0 = time.perf_counter()
        startup = t0 - t_start
        # Largest files first: the longest jobs start early, so the last
        # minutes of a batch are not one big mesh running on one worker while
        # the others idle (spin-willmore on the shared meshes: bunny_scan_35k
        # is 40 % of the total work and 13th in the manifest).
        order = sorted(todo, key=lambda s: -(os.path.getsize(s["input"]) if not s["missing"] else 0))
        try:
            futures = {client.submit(run_job, s, pure=False, key="curvflow-%s-%d" % (s["name"], os.getpid()),
                                     priority=len(order) - i): s
                       for i, s in enumerate(order)}
            done = 0
            for fut in as_completed(futures):
                s = futures[fut]
                try:
                    rec = fut.result()
                except Exception as e:  # the worker itself died (KilledWorker ...)
                    rec = {"mesh": s["name"], "input": s["input"], "status": "crashed",
                           "message": "the Dask worker failed: %s: %s" % (type(e).__name__, e)}
                records[s["name"]] = rec
                done += 1
                if not quiet:
                    print("[%d/%d] %s" % (done, len(todo), _one_line(rec)), flush=True)
            elapsed = time.perf_counter() - t0
        finally:
            if own_client is not None:
                own_client.close()
            if cluster is not None:
                cluster.close()
    ordered = [records[s["name"]] for s in specs]
    if report:
        for rec in ordered:
            if rec.get("output") and rec.get("status") == "ok":
                req = rec.get("request", {})
                params = [[k, str(v)] for k, v in sorted(req.get("params", {}).items())]
                if req.get("time_step") is not None:
                    params.insert(0, ["time_step", repr(req["time_step"])])
                run = {"command": "python3 -m curvflow.batch", "method": req.get("method"), "input": rec["input"],
                       "output": rec["output"], "log": rec.get("log"), "steps_requested": req.get("steps"),
                       "steps_done": rec.get("steps"), "parameters": params,
                       "seconds": {"run": rec.get("flow_seconds")} if rec.get("flow_seconds") else {}}
                try:
                    curvflow.report(rec["input"], rec["output"], log=rec.get("log"), run=run,
                                    title="%s: %s" % (rec["mesh"], req.get("method")),
                                    out=os.path.join(out, rec["mesh"] + ".html"))
                except curvflow.CurvflowError as e:
                    if not quiet:
                        print("curvflow.batch: report of %s: %s" % (rec["mesh"], e), flush=True)
    write_summary(os.path.join(out, "summary.csv"), ordered)
    if not quiet:
        ok = sum(r.get("status") == "ok" for r in ordered)
        rate = 60.0 * len(todo) / elapsed if todo and elapsed > 0 else 0.0
        print("curvflow.batch: %d ok, %d failed; %d run in %.1f s (%.1f meshes/min; cluster start %.1f s); "
              "summary: %s" % (ok, len(ordered) - ok, len(todo), elapsed, rate, startup,
                               os.path.join(out, "summary.csv")), flush=True)
    return ordered


def _one_line(rec):
    s = "%s: %s" % (rec.get("mesh"), rec.get("status"))
    if rec.get("status") == "ok":
        w0, w1 = rec.get("willmore_over_4pi_before"), rec.get("willmore_over_4pi_after")
        s += ", %s steps" % rec.get("steps")
        if w0 is not None and w1 is not None:
            s += ", W/4pi %.4g -> %.4g" % (w0, w1)
        if rec.get("q_max") is not None:
            s += ", Q mean %.4f max %.4f" % (rec["q_mean"], rec["q_max"])
    elif rec.get("message"):
        s += ": " + rec["message"]
    return s + ", %.1f s" % rec.get("seconds", 0.0)


def main(argv=None):
    import curvflow
    args = _parse_args(argv)
    params = {}
    for item in args.param:
        key, eq, value = item.partition("=")
        if not eq or not key:
            print("curvflow.batch: --param: expected KEY=VALUE, got '%s'" % item, file=sys.stderr)
            return 1
        params[key] = value  # as text: the library parses it, as for the CLI's --param
    if args.scheduler and args.workers:
        print("curvflow.batch: --workers is for the LocalCluster; the scheduler's workers are used",
              file=sys.stderr)
    try:
        records = run_batch(args.manifest, args.method, args.out, args.steps, args.time_step, params, args.format,
                            args.scheduler, args.workers, args.timeout, args.job_threads, args.allow_missing,
                            args.report, args.quiet)
    except (ManifestError, curvflow.UsageError) as e:
        print("curvflow.batch: %s" % e, file=sys.stderr)
        return 1
    return 0 if all(r.get("status") == "ok" for r in records) else 2


if __name__ == "__main__":
    # Re-import under the package name so that Dask pickles run_job as
    # curvflow.batch.run_job (a function of __main__ cannot be loaded by workers).
    from curvflow.batch import main as _main
    sys.exit(_main())
