"""Python results equal the CLI's on the same inputs, bit for bit.

The CLI writes its results as OBJ (positions printed with %.17g, which
strtod reads back exactly) or binary PLY (raw doubles); both are read back
with curvflow.load and compared with np.array_equal, i.e. exactly. The
per-step logs are compared field by field too (JSONL with 17 significant
digits), except the timings.
"""
import json
import math

import numpy as np
import pytest

import curvflow
from conftest import read_jsonl, run_cli

# method -> (mesh, CLI arguments, the same as Python keyword arguments)
CASES = [
    ("explicit-mcf", "bumpy", ["--steps", "6"], dict(steps=6)),
    ("explicit-mcf", "grid", ["--steps", "4", "-p", "mass=voronoi", "-p", "rescale=true"],
     dict(steps=4, mass="voronoi", rescale=True)),
    ("implicit-mcf", "bumpy", ["--steps", "5", "--time-step", "0.002"], dict(steps=5, time_step=0.002)),
    ("conformal-mcf", "torus", ["--steps", "5", "-p", "rescale=true"], dict(steps=5, rescale=True)),
    ("explicit-bilaplacian", "icosphere", ["--steps", "5", "-p", "tolerance=1e-12"],
     dict(steps=5, tolerance=1e-12)),
    ("implicit-bilaplacian", "bumpy", ["--steps", "4", "--time-step", "3.3e-6"], dict(steps=4, time_step=3.3e-6)),
    ("spin-willmore", "bumpy", ["--steps", "6"], dict(steps=6)),
    ("spin-willmore", "bumpy", ["--steps", "3", "-p", "sigma=0.25", "-p", "filter_k=1", "-p", "mobius=true"],
     dict(steps=3, sigma=0.25, filter_k=1, mobius=True)),
    ("spin-willmore", "torus", ["--steps", "3", "--time-step", "0.3"], dict(steps=3, time_step=0.3)),
    ("spin-willmore", "cylinder", ["--steps", "3", "-p", "boundary=fixed"], dict(steps=3, boundary="fixed")),
    ("spin-willmore", "limbs", ["--steps", "4", "-p", "relaxation=10"], dict(steps=4, relaxation=10)),
    # the default relaxes this closed genus-0 star (relaxation -1 resolves to 10 sweeps)
    ("spin-willmore", "limbs", ["--steps", "4"], dict(steps=4)),
]


def _compare_logs(cli_log, py_log):
    assert len(cli_log) == len(py_log)
    for a, b in zip(cli_log, py_log):
        for key in ("iteration", "time", "time_step", "energy", "terms", "residuals", "area", "volume",
                    "area_drift", "volume_drift"):
            assert a[key] == b[key], "%s: CLI %r, Python %r" % (key, a[key], b[key])
        assert set(a["seconds"]) == set(b["seconds"])


def test_every_cli_method_is_covered(cli):
    listed = [line.split()[0] for line in run_cli(cli, "flow", "--list-methods").stdout.splitlines()]
    assert listed == list(curvflow.methods())
    covered = {c[0] for c in CASES} | {"stretch-bend-edit"}  # edit: tests below
    assert covered == set(listed)


@pytest.mark.parametrize("method,mesh,cli_args,kwargs", CASES,
                         ids=["%s-%s-%d" % (c[0], c[1], i) for i, c in enumerate(CASES)])
def test_flow_equals_cli(cli, meshes, tmp_path, method, mesh, cli_args, kwargs):
    out, log = tmp_path / "out.obj", tmp_path / "log.jsonl"
    run_cli(cli, "flow", meshes[mesh], "-o", out, "--method", method, "--log", log, "-q", *cli_args)
    V, F, _ = curvflow.load(meshes[mesh])
    V_out, py_log = curvflow.flow(V, F, method, **kwargs)
    expected, F2, _ = curvflow.load(out)
    assert np.array_equal(F, F2)
    assert np.array_equal(V_out, expected), "max |diff| %g" % np.abs(V_out - expected).max()
    assert not np.array_equal(V_out, V)  # the flow moved the mesh
    _compare_logs(read_jsonl(log), py_log)


def test_flow_equals_cli_on_spot(cli, shared, tmp_path):
    out, log = tmp_path / "spot.ply", tmp_path / "log.jsonl"
    run_cli(cli, "flow", shared / "spot_3k.obj", "-o", out, "--method", "spin-willmore", "--steps", "10",
            "--log", log, "-q")
    V, F, _ = curvflow.load(shared / "spot_3k.obj")
    V_out, py_log = curvflow.flow(V, F, "spin-willmore", steps=10)
    assert np.array_equal(V_out, curvflow.load(out)[0])
    _compare_logs(read_jsonl(log), py_log)
    # the paper's Fig. 1 claim the C tests check: spot becomes round
    assert py_log[0]["energy"] / (4 * np.pi) > 10 and curvflow.info(V_out, F)["willmore_over_4pi"] < 1.2


def test_boundary_targets_equal_cli_file(cli, meshes, tmp_path):
    """spin-willmore's array parameter boundary_targets equals the CLI's
    --boundary-targets file (every boundary vertex, 17 digits)."""
    V, F, _ = curvflow.load(meshes["cylinder"])
    z = V[:, 2]
    rim0, rim1 = np.flatnonzero(z == z.min()), np.flatnonzero(z == z.max())
    targets = np.zeros_like(V)
    targets[rim0] = (0.0, 0.0, -1.0)
    targets[rim1] = (0.0, np.sin(0.3), np.cos(0.3))
    tf = tmp_path / "targets.txt"
    tf.write_text("".join("%d %r %r %r\n" % ((i,) + tuple(targets[i])) for i in np.concatenate([rim0, rim1])))
    out = tmp_path / "out.obj"
    run_cli(cli, "flow", meshes["cylinder"], "-o", out, "--method", "spin-willmore", "--steps", "3",
            "--boundary-targets", tf, "-q")
    V_out, _ = curvflow.flow(V, F, "spin-willmore", steps=3, boundary_targets=targets)
    assert np.array_equal(V_out, curvflow.load(out)[0])
    # and it is not the default (free boundary) result
    V_free, _ = curvflow.flow(V, F, "spin-willmore", steps=3)
    assert not np.array_equal(V_out, V_free)


@pytest.mark.parametrize("energy", ["hybrid", "arap", "bend"])
def test_edit_equals_cli(cli, meshes, tmp_path, energy):
    """curvflow.edit and flow(..., "stretch-bend-edit", handles=...) with a
    handle file, the same JSON as a dict, or (vertices, targets) arrays equal
    `curvflow edit`."""
    handles = {"sets": [{"name": "left", "relative_box": {"min": [0, 0, 0], "max": [0.05, 1, 1]}, "fixed": True},
                        {"name": "right", "relative_box": {"min": [0.95, 0, 0], "max": [1, 1, 1]},
                         "transform": {"rotate": {"axis": [1, 0, 0], "angle_degrees": 60}}}]}
    hf = tmp_path / "handles.json"
    hf.write_text(json.dumps(handles))
    out, log = tmp_path / "edit.obj", tmp_path / "log.jsonl"
    run_cli(cli, "edit", meshes["bar"], "--handles", hf, "--energy", energy, "--iterations", "12", "-o", out,
            "--log", log, "-q")
    expected = curvflow.load(out)[0]
    V, F, _ = curvflow.load(meshes["bar"])
    a, log_a = curvflow.edit(V, F, str(hf), energy=energy, iterations=12)
    b, _ = curvflow.edit(V, F, handles, energy=energy, iterations=12)
    c, _ = curvflow.flow(V, F, "stretch-bend-edit", steps=12, handles=hf, energy=energy)
    assert np.array_equal(a, expected) and np.array_equal(b, expected) and np.array_equal(c, expected)
    # `curvflow flow --method stretch-bend-edit --handles FILE` is the same run
    out_flow = tmp_path / "flow.obj"
    run_cli(cli, "flow", meshes["bar"], "-o", out_flow, "--method", "stretch-bend-edit", "--handles", hf,
            "--steps", "12", "-p", "energy=" + energy, "-q")
    assert np.array_equal(curvflow.load(out_flow)[0], c)
    _compare_logs(read_jsonl(log), log_a)
    # explicit arrays: the vertices the file selects with the targets it gives
    moved = np.flatnonzero(np.any(expected != V, axis=1))
    fixed_and_moved = np.flatnonzero((V[:, 0] <= V[:, 0].min() + 0.05 * np.ptp(V[:, 0])) |
                                     (V[:, 0] >= V[:, 0].max() - 0.05 * np.ptp(V[:, 0])))
    assert len(moved) > len(V) // 2
    d, _ = curvflow.edit(V, F, (fixed_and_moved, expected[fixed_and_moved]), energy=energy, iterations=12)
    assert np.allclose(d[fixed_and_moved], expected[fixed_and_moved], rtol=0, atol=1e-12)


def test_edit_lambda_and_start_equal_cli(cli, meshes, tmp_path):
    hf = tmp_path / "h.json"
    hf.write_text(json.dumps({"sets": [
        {"name": "a", "relative_box": {"min": [0, 0, 0], "max": [0.1, 1, 1]}, "fixed": True},
        {"name": "b", "relative_box": {"min": [0.9, 0, 0], "max": [1, 1, 1]},
         "transform": {"translate": [0, 1.5, 0]}}]}))
    start = tmp_path / "start.obj"
    run_cli(cli, "flow", meshes["bar"], "-o", start, "--method", "implicit-mcf", "--steps", "1", "-q")
    out = tmp_path / "out.obj"
    run_cli(cli, "edit", meshes["bar"], "--handles", hf, "--lambda", "0.25", "--start", start, "--iterations", "5",
            "--mass", "barycentric", "-o", out, "-q")
    V, F, _ = curvflow.load(meshes["bar"])
    S = curvflow.load(start)[0]
    got, _ = curvflow.edit(V, F, hf, lambda_=0.25, start=S, iterations=5, mass="barycentric")
    assert np.array_equal(got, curvflow.load(out)[0])


def test_edit_arap_weights_equal_cli(cli, meshes, tmp_path):
    """arap_weights="clamped" is --arap-weights clamped; beside a needle
    triangle (179.6 degrees) it keeps the vertices that the paper's weights
    pull off (docs/edit.md, "ARAP edge weights")."""
    V, F, _ = curvflow.load(meshes["bumpy"])
    v = int(np.argmin(np.abs(V[:, 1]) + np.abs(V[:, 0] - 1)))
    f = F[np.flatnonzero((F == v).any(axis=1))[0]]
    k = int(np.flatnonzero(f == v)[0])
    mid = 0.5 * (V[f[(k + 1) % 3]] + V[f[(k + 2) % 3]])
    V[v] = mid + 0.003 * (V[v] - mid)
    needle = tmp_path / "needle.obj"
    curvflow.save(needle, V, F)
    hf = tmp_path / "h.json"
    hf.write_text(json.dumps({"sets": [
        {"name": "base", "relative_box": {"min": [0, 0, 0], "max": [1, 0.1, 1]}, "fixed": True},
        {"name": "top", "relative_box": {"min": [0, 0.9, 0], "max": [1, 1, 1]},
         "transform": {"rotate": {"axis": [1, 0, 0], "angle_degrees": 30}}}]}))
    diag = np.linalg.norm(np.ptp(V, axis=0))
    moves = {}
    for weights in ("cotan", "clamped"):
        out = tmp_path / (weights + ".obj")
        done = run_cli(cli, "edit", needle, "--handles", hf, "--energy", "arap", "--arap-weights", weights,
                       "-o", out, "-q")
        got, log = curvflow.edit(V, F, str(hf), energy="arap", arap_weights=weights)
        assert np.array_equal(got, curvflow.load(out)[0])
        moves[weights] = np.linalg.norm(got - V, axis=1).max() / diag
        assert ("energy is negative" in done.stderr) == (weights == "cotan")
        assert (min(step["energy"] for step in log) < 0) == (weights == "cotan")
    assert moves["cotan"] > 0.5 and moves["clamped"] < 0.15
    with pytest.raises(curvflow.UsageError):
        curvflow.edit(V, F, str(hf), energy="arap", arap_weights="uniform")

def test_spin_equals_cli(cli, meshes, tmp_path):
    V, F, _ = curvflow.load(meshes["bumpy"])
    rho = 0.3 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
    rf = tmp_path / "rho.txt"
    rf.write_text("".join("%r\n" % r for r in rho))
    out = tmp_path / "spun.ply"
    run_cli(cli, "spin", meshes["bumpy"], "--rho", rf, "-o", out)
    got = curvflow.spin(V, F, rho)
    V2, _, extras = curvflow.load(out)
    assert np.array_equal(got, V2)
    assert np.array_equal(extras["vertex_fields"]["rho"], rho)  # the CLI stores rho in the PLY
    assert extras["uv"] is not None  # texture coordinates kept


def test_compare_equals_cli(cli, meshes, tmp_path):
    V, F, _ = curvflow.load(meshes["bumpy"])
    V2, _ = curvflow.flow(V, F, "spin-willmore", steps=4)
    b = tmp_path / "b.ply"
    curvflow.save(b, V2, F)
    ply = tmp_path / "q.ply"
    js = json.loads(run_cli(cli, "compare", meshes["bumpy"], b, "--json", "--ply", ply).stdout)
    got = curvflow.compare(V, V2, F)
    extras = curvflow.load(ply)[2]
    fields = extras["face_fields"]
    assert np.array_equal(got["Q"], fields["Q"])
    assert np.array_equal(got["log_scale"], extras["vertex_fields"]["log_scale"])
    assert np.array_equal(got["log_area_distortion_per_face"], fields["log_area_distortion"])
    for key in ("quasi_conformal_error", "log_area_distortion", "angle_change", "vertex_scale_model_q"):
        for stat in ("mean", "std", "min", "median", "p95", "max"):
            # --json prints 10 significant digits
            assert got[key][stat] == pytest.approx(js[key][stat], rel=1e-9, abs=1e-300)
    model = got["vertex_scale_model_q"]
    assert model["invalid_faces"] == js["vertex_scale_model_q"]["invalid_faces"] == 0
    assert model["rms_log_length_residual"] == pytest.approx(js["vertex_scale_model_q"]["rms_log_length_residual"],
                                                             rel=1e-9)
    assert 1.0 < got["quasi_conformal_error"]["mean"] < 1.1  # a conformal flow: Q near 1
    # a conformal flow: its excess Q - 1 is the vertex-scale model's (0.01500 against 0.01504, measured)
    assert model["mean"] - 1.0 == pytest.approx(got["quasi_conformal_error"]["mean"] - 1.0, rel=0.02)
    assert model["rms_log_length_residual"] < 1e-3
    assert got["log_scale"].shape == (len(V),) and got["vertex_scale_model_q_per_face"].shape == (len(F),)
    assert got["faces"] == js["faces"] == len(F)
    assert got["conformal_class"] is None and js["conformal_class"] is None  # genus 0: one class


def test_compare_conformal_class_equals_cli(cli, tmp_path):
    """On a torus `compare` also measures the conformal class (docs/ops.md,
    "Conformal class"): Python and the CLI agree, and a torus of revolution
    with radii 1, 0.4 has the modulus sqrt(1 - 0.16) / 0.4 = 2.2913 i (2.2981 at
    48 x 24, measured)."""
    a, b = tmp_path / "a.obj", tmp_path / "b.obj"
    run_cli(cli, "generate", "torus", "-o", a)
    run_cli(cli, "generate", "torus", "--minor-radius", "0.3", "-o", b)
    V, F, _ = curvflow.load(a)
    W = curvflow.load(b)[0]
    js = json.loads(run_cli(cli, "compare", a, b, "--json").stdout)["conformal_class"]
    got = curvflow.compare(V, W, F)["conformal_class"]
    assert got["genus"] == js["genus"] == 1
    assert got["distance"] == pytest.approx(js["distance"], rel=1e-9)
    assert got["modulus_a"] == pytest.approx(js["modulus_a"], rel=1e-9, abs=1e-12)
    assert got["modulus_b"] == pytest.approx(js["modulus_b"], rel=1e-9, abs=1e-12)
    assert got["modulus_a"][1] == pytest.approx((1 - 0.4 ** 2) ** 0.5 / 0.4, rel=5e-3)
    assert got["modulus_b"][1] == pytest.approx((1 - 0.3 ** 2) ** 0.5 / 0.3, rel=5e-3)
    # genus 1: the hyperbolic distance of two rectangular moduli i b1, i b2 is |log(b2 / b1)|
    assert got["distance"] == pytest.approx(abs(math.log(got["modulus_b"][1] / got["modulus_a"][1])), rel=1e-3)


@pytest.mark.parametrize("mesh", ["bumpy", "grid", "torus"])
def test_info_equals_cli(cli, meshes, mesh):
    js = json.loads(run_cli(cli, "info", meshes[mesh], "--json").stdout)
    for got in (curvflow.info(meshes[mesh]), curvflow.info(*curvflow.load(meshes[mesh])[:2])):
        for key, value in js.items():
            if key in ("file", "texture_coordinates", "polygons_triangulated", "vertex_properties",
                       "face_properties", "material_libraries", "material_names", "seams") and "file" not in got:
                continue
            if isinstance(value, dict):
                for k, v in value.items():
                    assert got[key][k] == (pytest.approx(v, rel=1e-9) if isinstance(v, float) else v), (key, k)
            elif isinstance(value, float):
                assert got[key] == pytest.approx(value, rel=1e-9), key
            else:
                assert got[key] == value, key


def test_info_reports_invalid_file(cli, shared):
    path = shared / "bad" / "nonmanifold_edges_beetle.obj"
    js = json.loads(run_cli(cli, "info", path, "--json", check=False).stdout)
    got = curvflow.info(path)
    assert got["validation"]["valid"] is False
    assert got["validation"]["first_error"] == js["validation"]["first_error"]
    assert got["validation"]["nonmanifold_edges"] == js["validation"]["nonmanifold_edges"] > 0
    assert got["validation"]["first_status"] == "CF_ERR_NONMANIFOLD_EDGE"


def test_load_extras_and_save_round_trip(cli, meshes, tmp_path):
    """Texture coordinates and named fields survive load/save exactly, in
    PLY (binary and ASCII) and OBJ (+ side CSV files), and the CLI reads
    what Python writes."""
    V, F, extras = curvflow.load(meshes["bumpy"])
    assert extras["uv"].shape[1] == 2 and extras["uv_faces"].shape == F.shape  # per-corner uv
    q = np.linspace(1.0, 2.0, len(F)) ** 0.5
    h = np.cos(V[:, 2]) / 3
    for name in ("r.ply", "r_ascii.ply", "r.obj"):
        path = tmp_path / name
        curvflow.save(path, V, F, fields={"Q": q, "h": h}, uv=extras["uv"], uv_faces=extras["uv_faces"],
                      ply_encoding="ascii" if "ascii" in name else "binary")
        V2, F2, ex2 = curvflow.load(path)
        assert np.array_equal(V2, V) and np.array_equal(F2, F)
        assert np.array_equal(ex2["uv"][ex2["uv_faces"]], extras["uv"][extras["uv_faces"]])
        if name.endswith(".ply"):
            assert np.array_equal(ex2["face_fields"]["Q"], q) and np.array_equal(ex2["vertex_fields"]["h"], h)
        else:
            face_csv = np.loadtxt(tmp_path / "r.face.csv", delimiter=",", skiprows=1)
            assert np.array_equal(face_csv[:, 1], q)
        info = json.loads(run_cli(cli, "info", path, "--json").stdout)
        assert info["texture_coordinates"] == "per-corner" and info["vertices"] == len(V)


def test_obj_materials_round_trip_and_cli(cli, meshes, tmp_path):
    """An OBJ's mtllib / usemtl survive load -> save exactly as the CLI's
    flow keeps them (the same file both ways); other formats refuse them;
    bad material lists are refused naming what is wrong, writing nothing."""
    V, F, extras = curvflow.load(meshes["icosphere"])
    assert extras["material_libraries"] == [] and extras["material_names"] == [] and extras["face_materials"] is None
    mat = np.where(np.arange(len(F)) < 7, -1, np.arange(len(F)) % 3).astype(np.int32)
    names = ["skin", "spots", "ünïcode name"]
    src = tmp_path / "textured.obj"
    curvflow.save(src, V, F, material_libraries=["skin.mtl", "sub dir/b.mtl"], material_names=names,
                  face_materials=mat)
    _, _, ex = curvflow.load(src)
    # names come back in order of first use (the file holds no other order): compare each face's name
    assert ex["material_libraries"] == ["skin.mtl", "sub dir/b.mtl"] and sorted(ex["material_names"]) == sorted(names)
    assert ex["face_materials"].dtype == np.int32
    assert [ex["material_names"][i] if i >= 0 else None for i in ex["face_materials"]] == \
        [names[i] if i >= 0 else None for i in mat]
    js = json.loads(run_cli(cli, "info", src, "--json").stdout)
    assert js["material_libraries"] == ["skin.mtl", "sub dir/b.mtl"] and js["material_names"] == ex["material_names"]
    assert curvflow.info(src)["material_names"] == ex["material_names"]
    # the CLI's flow output and Python's flow + save of the same run are the same file
    run_cli(cli, "flow", src, "-o", tmp_path / "cli.obj", "--method", "spin-willmore", "--steps", "1", "-q")
    state, _ = curvflow.flow(V, F, "spin-willmore", steps=1)
    keep = {k: ex[k] for k in ("material_libraries", "material_names", "face_materials")}
    curvflow.save(tmp_path / "py.obj", state, F, **keep)
    assert (tmp_path / "cli.obj").read_bytes() == (tmp_path / "py.obj").read_bytes()
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(curvflow.UsageError, match=r"x\.ply: materials \(mtllib / usemtl\) can only be written to an OBJ"):
        curvflow.save(tmp_path / "x.ply", V, F, **keep)
    with pytest.raises(curvflow.UsageError, match=r"face 7 has material 4, expected -1 \.\. 2"):
        curvflow.save(tmp_path / "x.obj", V, F, material_names=names, face_materials=mat + (np.arange(len(F)) == 7) * 3)
    with pytest.raises(curvflow.UsageError, match=r"face_materials has 3 entries, F has 320 faces"):
        curvflow.save(tmp_path / "x.obj", V, F, material_names=names, face_materials=[0, 1, 2])
    with pytest.raises(curvflow.UsageError, match=r"face_materials given without material_names"):
        curvflow.save(tmp_path / "x.obj", V, F, face_materials=mat)
    with pytest.raises(curvflow.UsageError, match=r"material 1's name is empty or holds a line break"):
        curvflow.save(tmp_path / "x.obj", V, F, material_names=["a", "b\nusemtl c"], face_materials=mat * 0)
    with pytest.raises(TypeError, match=r"material_names: expected a list of str, got 'skin'"):
        curvflow.save(tmp_path / "x.obj", V, F, material_names="skin")
    with pytest.raises(TypeError, match=r"material_libraries: expected a list of str"):
        curvflow.save(tmp_path / "x.obj", V, F, material_libraries=[b"skin.mtl"])
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_save_refuses_fields_in_off(meshes, tmp_path):
    V, F, _ = curvflow.load(meshes["icosphere"])
    with pytest.raises(curvflow.UnsupportedError, match="off"):
        curvflow.save(tmp_path / "x.off", V, F, fields={"a": np.zeros(len(V))})
    assert not (tmp_path / "x.off").exists()
