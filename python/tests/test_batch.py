"""python3 -m curvflow.batch on a LocalCluster with two workers: one job
process per mesh, failures (bad file, crash, timeout) recorded per mesh
while the others finish, results equal to curvflow.flow's, atomic outputs,
and a rerun that skips completed meshes."""
import csv
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import curvflow
from conftest import ROOT

pytest.importorskip("distributed", reason="SKIP: Debian's python3-distributed is not installed")

SHARED_FEW = ["cactus_620.obj", "spool_creases_650.obj", "hand_1k.obj"]


def run_batch(*args, env_extra=None, timeout=300):
    env = dict(os.environ, PYTHONPATH=str(ROOT / "python"))
    env.update(env_extra or {})
    return subprocess.run([sys.executable, "-m", "curvflow.batch"] + [str(a) for a in args], capture_output=True,
                          text=True, env=env, timeout=timeout)


def read_summary(out):
    with open(out / "summary.csv", newline="", encoding="utf-8") as fp:
        return {row["mesh"]: row for row in csv.DictReader(fp)}


@pytest.fixture(scope="module")
def data(meshes, tmp_path_factory):
    """A manifest over generated meshes, a few shared ones (when present),
    the shared non-manifold file, a truncated file, a mesh whose job
    crashes and one that runs into the timeout."""
    d = tmp_path_factory.mktemp("batch")
    truncated = d / "truncated.obj"
    text = meshes["icosphere"].read_text()
    truncated.write_text(text[: int(len(text) * 0.8)].rsplit("\n", 1)[0] + "\nf 1 2")
    rows = [("path", "name", "steps", "time_step"),
            (meshes["icosphere"], "", "", ""), (meshes["bumpy"], "", "", ""), (meshes["torus"], "", "", ""),
            (truncated, "", "", ""), (meshes["bumpy"], "crashy", "", ""),
            (meshes["bumpy"], "slow", 10**8, 1e-9)]
    from conftest import shared_meshes
    shared = shared_meshes()
    if shared is not None:
        rows += [(shared / m, "", "", "") for m in SHARED_FEW]
        rows.append((shared / "bad" / "nonmanifold_edges_beetle.obj", "", "", ""))
    manifest = d / "manifest.csv"
    with open(manifest, "w", newline="") as fp:
        csv.writer(fp).writerows(rows)
    return d, manifest, shared is not None


def test_batch_two_workers(data, meshes):
    d, manifest, with_shared = data
    out = d / "out"
    proc = run_batch(manifest, "--method", "implicit-mcf", "--steps", "4", "--out", out, "--workers", "2",
                     "--timeout", "4", "--format", "ply", env_extra={"CURVFLOW_BATCH_FAULT": "crash:crashy"})
    assert proc.returncode == 2, proc.stderr  # ran, some meshes failed
    rows = read_summary(out)
    ok = ["icosphere", "bumpy", "torus"] + ([m[:-4] for m in SHARED_FEW] if with_shared else [])
    for name in ok:
        assert rows[name]["status"] == "ok", rows[name]
    assert rows["truncated"]["status"] == "invalid-mesh"
    assert "truncated.obj: line" in rows["truncated"]["message"]
    # "died with SIGSEGV", or ASan's "SEGV" report in a sanitizer build
    assert rows["crashy"]["status"] == "crashed" and "SEGV" in rows["crashy"]["message"]
    assert rows["slow"]["status"] == "timeout"
    assert rows["slow"]["last_good"].endswith("slow.last_good.ply") and int(rows["slow"]["steps"]) > 0
    if with_shared:
        beetle = rows["nonmanifold_edges_beetle"]
        assert beetle["status"] == "invalid-mesh" and "edge (135, 136) is shared by 3 faces" in beetle["message"]
    # both workers took jobs
    assert len({r["worker"] for r in rows.values()}) == 2
    # one line per mesh in manifest order, every column present
    with open(out / "summary.csv", newline="", encoding="utf-8") as fp:
        reader = csv.reader(fp)
        header = next(reader)
        assert header[:12] == ["mesh", "status", "message", "steps", "energy_before", "energy_after",
                               "willmore_over_4pi_before", "willmore_over_4pi_after", "q_mean", "q_max",
                               "seconds", "output"]
        assert [r[0] for r in reader][:3] == ["icosphere", "bumpy", "torus"]
    # results are the Python API's, bit for bit, and the figures are right
    V, F, extras = curvflow.load(meshes["bumpy"])
    ref, log = curvflow.flow(V, F, "implicit-mcf", steps=4)
    got, F2, ex2 = curvflow.load(out / "bumpy.ply")
    assert np.array_equal(got, ref) and np.array_equal(F2, F)
    assert ex2["uv"] is not None  # texture coordinates kept
    b = rows["bumpy"]
    assert int(b["steps"]) == 4 and float(b["energy_after"]) == log[-1]["energy"]
    assert float(b["willmore_over_4pi_before"]) == curvflow.info(V, F)["willmore_over_4pi"]
    assert float(b["willmore_over_4pi_after"]) == curvflow.info(ref, F)["willmore_over_4pi"]
    q = curvflow.compare(V, ref, F)["quasi_conformal_error"]
    assert float(b["q_mean"]) == q["mean"] and float(b["q_max"]) == q["max"]
    stored = curvflow.read_log(out / "bumpy.log.jsonl")
    for entry in stored + log:
        del entry["seconds"]  # timings differ between runs
    assert stored == log
    # the timed-out mesh's last good state is a complete mesh
    assert curvflow.load(out / "slow.last_good.ply")[0].shape == V.shape
    # nothing half-written: only finished files, no temporaries
    assert not [p for p in os.listdir(out) if ".tmp" in p or p.startswith(".")]
    # per-mesh records
    rec = json.loads((out / "crashy.json").read_text())
    assert rec["status"] == "crashed" and rec["request"]["method"] == "implicit-mcf"

    # rerun: completed meshes are skipped (files untouched), failed ones rerun
    mtimes = {p: p.stat().st_mtime_ns for p in out.glob("*.ply")}
    proc = run_batch(manifest, "--method", "implicit-mcf", "--steps", "4", "--out", out, "--workers", "2",
                     "--timeout", "4", "--format", "ply", "--report")
    assert proc.returncode == 2
    assert "%d of %d meshes already complete" % (len(ok), len(rows)) in proc.stdout
    rows2 = read_summary(out)
    for name in ok:
        assert rows2[name]["skipped"] == "True" and rows2[name]["status"] == "ok"
        assert (out / (name + ".ply")).stat().st_mtime_ns == mtimes[out / (name + ".ply")]
    assert rows2["crashy"]["status"] == "ok"  # no fault injected this time
    # --report: one HTML report per completed mesh through curvflow.report (when the tool has the viewer)
    if "report of" not in proc.stdout:
        assert sorted(p.stem for p in out.glob("*.html")) == sorted(ok + ["crashy"])
        assert "bumpy: implicit-mcf" in (out / "bumpy.html").read_text()
    assert rows2["truncated"]["status"] == "invalid-mesh"


def test_batch_different_request_reruns(data, tmp_path, meshes):
    """A stored result counts as complete only for the same request."""
    manifest = tmp_path / "m.csv"
    manifest.write_text("path\n%s\n" % meshes["icosphere"])
    out = tmp_path / "out"
    assert run_batch(manifest, "--method", "implicit-mcf", "--steps", "2", "--out", out, "--workers", "1",
                     "-q").returncode == 0
    proc = run_batch(manifest, "--method", "implicit-mcf", "--steps", "3", "--out", out, "--workers", "1")
    assert proc.returncode == 0 and "already complete" not in proc.stdout
    assert read_summary(out)["icosphere"]["steps"] == "3"


def test_manifest_and_usage_errors(tmp_path, meshes):
    out = tmp_path / "out"
    m = tmp_path / "missing.csv"
    m.write_text("path\n%s\nnot_here.obj\n" % meshes["icosphere"])
    proc = run_batch(m, "--method", "implicit-mcf", "--out", out)
    assert proc.returncode == 1
    assert "1 mesh file is missing (line 3: %s)" % (tmp_path / "not_here.obj") in proc.stderr
    assert "--allow-missing" in proc.stderr and not out.exists()
    proc = run_batch(m, "--method", "implicit-mcf", "--out", out, "--allow-missing", "--workers", "1")
    assert proc.returncode == 2
    rows = read_summary(out)
    assert rows["not_here"]["status"] == "missing" and rows["icosphere"]["status"] == "ok"

    nocol = tmp_path / "nocol.csv"
    nocol.write_text("filename\nx.obj\n")
    proc = run_batch(nocol, "--method", "implicit-mcf", "--out", out)
    assert proc.returncode == 1 and "no mesh column (expected one of path, file, mesh, got filename)" in proc.stderr
    dup = tmp_path / "dup.csv"
    dup.write_text("path\n%s\n%s\n" % (meshes["icosphere"], meshes["icosphere"]))
    proc = run_batch(dup, "--method", "implicit-mcf", "--out", out)
    assert proc.returncode == 1 and "output name 'icosphere' is already used on line 2" in proc.stderr
    proc = run_batch(tmp_path / "nope.csv", "--method", "implicit-mcf", "--out", out)
    assert proc.returncode == 1 and "nope.csv: cannot read the manifest" in proc.stderr
    proc = run_batch(m, "--method", "spin-wilmore", "--out", out)
    assert proc.returncode == 1 and "unknown method 'spin-wilmore'" in proc.stderr
    proc = run_batch(m, "--method", "spin-willmore", "-p", "sigmaa=2", "--out", out)
    assert proc.returncode == 1 and "parameter 'sigmaa': unknown for method spin-willmore" in proc.stderr



def test_file_names_with_spaces(tmp_path, meshes):
    """A mesh file named as users name them ("scan 01 (left).obj") runs
    under a default name made of its stem, every character other than
    letters, digits and -_. made _ (it was refused as "not a plain file
    stem" unless the manifest gave a name); a given name must still be
    plain. A PLY's vertex and face properties reach the output (they were
    dropped)."""
    d = tmp_path / "my scans"
    d.mkdir()
    (d / "scan 01 (left).obj").write_text(meshes["icosphere"].read_text())
    (d / "ïcö.obj").write_text(meshes["torus"].read_text())
    m = d / "manifest.csv"
    m.write_text("path\nscan 01 (left).obj\nïcö.obj\n", encoding="utf-8")
    out = tmp_path / "out"
    proc = run_batch(m, "--method", "implicit-mcf", "--steps", "2", "--out", out, "--workers", "1")
    assert proc.returncode == 0, proc.stderr
    rows = read_summary(out)
    assert rows["scan_01__left_"]["status"] == "ok" and rows["ïcö"]["status"] == "ok"
    assert (out / "scan_01__left_.ply").is_file()
    # a PLY's properties ride along to the output, as with the CLI's flow
    V, F, _ = curvflow.load(str(meshes["icosphere"]))
    red = (np.arange(len(V)) * 7 % 256).astype(float)
    label = (np.arange(len(F)) % 3).astype(float)
    curvflow.save(str(d / "coloured.ply"), V, F, vertex_fields={"red": red}, face_fields={"label": label})
    m.write_text("path\ncoloured.ply\n", encoding="utf-8")
    proc = run_batch(m, "--method", "spin-willmore", "--steps", "2", "--out", out, "--workers", "1")
    assert proc.returncode == 0, proc.stderr
    V2, _, extras = curvflow.load(str(out / "coloured.ply"))
    assert np.array_equal(extras["vertex_fields"]["red"], red)
    assert np.array_equal(extras["face_fields"]["label"], label)
    assert not np.array_equal(V2, V)
    # and an OBJ's materials to an OBJ result, the library named from the output directory
    Vi, Fi, _ = curvflow.load(str(meshes["icosphere"]))
    mat = (np.arange(len(Fi)) % 2).astype(np.int32)
    curvflow.save(str(d / "textured.obj"), Vi, Fi, material_libraries=["skin.mtl"], material_names=["a", "b"],
                  face_materials=mat)
    m.write_text("path\ntextured.obj\n", encoding="utf-8")
    proc = run_batch(m, "--method", "spin-willmore", "--steps", "1", "--out", out, "--workers", "1",
                     "--format", "obj")
    assert proc.returncode == 0, proc.stderr
    _, _, extras = curvflow.load(str(out / "textured.obj"))
    assert extras["material_libraries"] == [os.path.join(os.path.realpath(d), "skin.mtl")]
    assert extras["material_names"] == ["a", "b"] and np.array_equal(extras["face_materials"], mat)
    m.write_text("path,name\nscan 01 (left).obj,my scan\n", encoding="utf-8")
    proc = run_batch(m, "--method", "implicit-mcf", "--out", out)
    assert proc.returncode == 1 and "name 'my scan' is not a plain file stem (letters, digits" in proc.stderr

def test_shared_manifest_tsv_is_read(shared):
    """The shared meshes' MANIFEST.tsv (a `file` column, tab-separated) is a
    valid manifest: 20 meshes, all present."""
    from curvflow.batch import read_manifest
    rows = read_manifest(shared / "MANIFEST.tsv")
    assert len(rows) == 20 and not any(r["missing"] for r in rows)
    assert rows[0]["name"] == "spot_3k" and rows[0]["input"] == str((shared / "spot_3k.obj").resolve())


def test_batch_on_a_running_scheduler(tmp_path, meshes, monkeypatch):
    """--scheduler ADDRESS uses an already running Dask scheduler and its
    workers (here a LocalCluster started by the test, standing for a cluster
    on other machines) instead of starting one."""
    from distributed import LocalCluster
    monkeypatch.setenv("PYTHONPATH", str(ROOT / "python"))  # the workers import curvflow.batch
    from curvflow.batch import _NANNY_ENVIRON
    for key in _NANNY_ENVIRON:  # the Nanny writes them into os.environ: restored after the test
        monkeypatch.setenv(key, "x")
        monkeypatch.delenv(key)
    manifest = tmp_path / "m.csv"
    manifest.write_text("path\n%s\n%s\n" % (meshes["icosphere"], meshes["torus"]))
    out = tmp_path / "out"
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=True, dashboard_address="127.0.0.1:0") as cluster:
        proc = run_batch(manifest, "--method", "conformal-mcf", "--steps", "3", "--out", out, "--scheduler",
                         cluster.scheduler_address)
        workers = set(cluster.scheduler_info["workers"])
    assert proc.returncode == 0, proc.stderr
    rows = read_summary(out)
    assert [r["status"] for r in rows.values()] == ["ok", "ok"]
    assert {r["worker"] for r in rows.values()} <= workers  # ran on the given cluster's worker


def test_run_batch_in_process_keeps_environment(tmp_path, meshes):
    """curvflow.batch.run_batch called from a script: the LocalCluster it
    starts leaves the caller's environment as it was (distributed's Nanny
    would leave OPENBLAS_NUM_THREADS=1 etc. behind, and the CLI run by the
    caller afterwards would compute with another BLAS thread count)."""
    from curvflow.batch import _NANNY_ENVIRON, run_batch as run_in_process
    before = {k: os.environ.get(k) for k in _NANNY_ENVIRON}
    manifest = tmp_path / "m.csv"
    manifest.write_text("path\n%s\n" % meshes["icosphere"])
    env_python = os.environ.get("PYTHONPATH")
    os.environ["PYTHONPATH"] = str(ROOT / "python")
    try:
        recs = run_in_process(manifest, "implicit-mcf", tmp_path / "out", steps=2, workers=1)
    finally:
        if env_python is None:
            os.environ.pop("PYTHONPATH")
        else:
            os.environ["PYTHONPATH"] = env_python
    assert [r["status"] for r in recs] == ["ok"]
    assert {k: os.environ.get(k) for k in _NANNY_ENVIRON} == before
