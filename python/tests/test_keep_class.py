"""spin-willmore's option keep_class on a closed surface of genus 2
(docs/spin.md, "The conformal class the flow keeps"): the generated double
torus leaves its conformal class by 0.35 in 10 default steps and ends at mean
Q 1.80, and the run's note names both modes and the distance (and the
tangential relaxation, unless it was asked for). keep_class=1
holds the class (to 1e-8), W still falls at every step and below the
default's, mean Q falls to 1.51 and the note names the second mode;
keep_class=2 also holds the Gram matrix (the triangulation's part of it),
mean Q stays under 1.5 and no note is written. The CLI and Python give the
same result, byte for byte."""
import curvflow
import numpy as np
from conftest import read_jsonl, run_cli


def test_keep_class_on_the_double_torus(cli, tmp_path):
    mesh = tmp_path / "dt.obj"
    run_cli(cli, "generate", "double-torus", "-o", mesh)
    V, F, _ = curvflow.load(mesh)
    default = run_cli(cli, "flow", mesh, "-o", tmp_path / "a.obj", "--method", "spin-willmore",
                      "--log", tmp_path / "a.jsonl")
    kept = run_cli(cli, "flow", mesh, "-o", tmp_path / "b.obj", "--method", "spin-willmore", "-p", "keep_class=1",
                   "--log", tmp_path / "b.jsonl")
    whole = run_cli(cli, "flow", mesh, "-o", tmp_path / "c.obj", "--method", "spin-willmore", "-p", "keep_class=2")
    a = curvflow.compare(V, curvflow.load(tmp_path / "a.obj")[0], F)
    b = curvflow.compare(V, curvflow.load(tmp_path / "b.obj")[0], F)
    c = curvflow.compare(V, curvflow.load(tmp_path / "c.obj")[0], F)
    # measured 0.35, 5e-11, 1e-14
    assert a["conformal_class"]["distance"] > 0.1
    assert b["conformal_class"]["distance"] < 1e-8 and c["conformal_class"]["distance"] < 1e-8
    # 1.80, 1.51, 1.29
    qa, qb, qc = (r["quasi_conformal_error"]["mean"] for r in (a, b, c))
    assert qa > qb > 1.5 > qc
    assert "-p keep_class=1" in default.stderr and "conformal class moved by 0.35" in default.stderr
    # the relaxation, not a default on genus > 0, is named where it did not run
    assert "-p relaxation=10 moves the vertices" in default.stderr
    relaxed = run_cli(cli, "flow", mesh, "-o", tmp_path / "d.obj", "--method", "spin-willmore", "-p", "relaxation=10")
    assert "-p keep_class=1" in relaxed.stderr and "-p relaxation=10" not in relaxed.stderr
    assert "-p keep_class=2" in kept.stderr and "with its conformal class held" in kept.stderr
    assert "note:" not in whole.stderr
    w_default = read_jsonl(tmp_path / "a.jsonl")[-1]["terms"]["W/4pi"]
    log = read_jsonl(tmp_path / "b.jsonl")
    w = [step["terms"]["W/4pi"] for step in log]
    assert all(y <= x for x, y in zip(w, w[1:])) and w[-1] < 0.5 * w[0] and w[-1] < w_default
    # the log's `class`: |G^ - G0^| after each step's projection
    assert all(0 <= step["residuals"]["class"] < 1e-8 for step in log[1:])
    V2, _ = curvflow.flow(V, F, "spin-willmore", steps=10, keep_class=1)
    assert np.array_equal(V2, curvflow.load(tmp_path / "b.obj")[0])
    V3, _ = curvflow.flow(V, F, "spin-willmore", steps=10, keep_class=2)
    assert np.array_equal(V3, curvflow.load(tmp_path / "c.obj")[0])


def test_keep_class_refused_on_a_sphere(cli, meshes, tmp_path):
    r = run_cli(cli, "flow", meshes["bumpy"], "-o", tmp_path / "a.obj", "--method", "spin-willmore", "-p",
                "keep_class=1", check=False)
    assert r.returncode == 2
    assert "keep_class needs a closed surface of genus >= 1" in r.stderr
