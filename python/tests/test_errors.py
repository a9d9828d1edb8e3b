"""Bad input: each case is a Python exception of the right class naming the
problem (the library's validation message where it applies), never a
crash; numerical failures keep the last good state."""
import numpy as np
import pytest

import curvflow
from conftest import run_cli


@pytest.fixture(scope="module")
def mesh(meshes):
    V, F, _ = curvflow.load(meshes["icosphere"])
    return V, F


# ---- arrays -----------------------------------------------------------------------

@pytest.mark.parametrize("make,exc,pattern", [
    (lambda V, F: (V[:, :2], F), curvflow.UsageError, r"V: expected shape \(n, 3\), got \(162, 2\)"),
    (lambda V, F: (V.reshape(-1), F), curvflow.UsageError, r"V: expected shape \(n, 3\), got \(486,\)"),
    (lambda V, F: (V, F[:, :2]), curvflow.UsageError, r"F: expected shape \(n, 3\), got \(320, 2\)"),
    (lambda V, F: (V.astype(np.complex128), F), TypeError, r"V: expected real coordinates .* complex128"),
    (lambda V, F: (V.astype(object), F), TypeError, r"V: expected real coordinates .* object"),
    (lambda V, F: (V, F.astype(np.float64)), TypeError, r"F: expected integer vertex indices .* float64 "
                                                        r"\(convert with \.astype\(np\.int32\)\)"),
    (lambda V, F: (V > 0, F), TypeError, r"V: expected real coordinates .* bool"),
    (lambda V, F: (np.repeat(V, 2, axis=0)[::2], F), curvflow.UsageError,
     r"V is a non-contiguous view \(shape \(162, 3\), strides \(48, 8\)\); pass np\.ascontiguousarray\(V\)"),
    (lambda V, F: (V, np.repeat(F, 2, axis=1)[:, ::2]), curvflow.UsageError, r"F is a non-contiguous view"),
    (lambda V, F: (V, np.where(F == 5, 162, F)), curvflow.InvalidMeshError,
     r"^face \d+: vertex index 162 out of range \[0, 162\)$"),
    (lambda V, F: (V, np.where(F == 5, -1, F)), curvflow.InvalidMeshError, r"^face \d+: vertex index -1 out of range"),
    (lambda V, F: (V, np.where(F == 5, 2**40, F.astype(np.int64))), curvflow.InvalidMeshError,
     r"F: row \d+: index 1099511627776 does not fit the library's int32 indices"),
    (lambda V, F: (np.where(np.arange(162)[:, None] == 7, np.nan, V), F), curvflow.InvalidMeshError,
     r"^vertex 7: coordinate x is NaN$"),
    (lambda V, F: (np.where(np.arange(162)[:, None] == 9, np.inf, V), F), curvflow.InvalidMeshError, r"^vertex 9: "),
    (lambda V, F: (V, np.concatenate([F, [[F[0, 0], F[0, 1], 100]]])), curvflow.InvalidMeshError,
     r"^face 320: edge \(\d+, \d+\) is shared by 3 faces$"),
    (lambda V, F: (V, F[:, ::-1].copy()[:1].repeat(1, 0).tolist() + F[1:].tolist()), curvflow.InvalidMeshError,
     r"same direction"),
    (lambda V, F: (V[:0], F[:0]), curvflow.InvalidMeshError, r"."),
])
def test_bad_arrays(mesh, make, exc, pattern):
    V, F = make(*mesh)
    for call in (lambda: curvflow.flow(V, F, "implicit-mcf", steps=1), lambda: curvflow.info(V, F)
                 if exc is not curvflow.InvalidMeshError else curvflow.compare(V, V, F)):
        with pytest.raises(exc, match=pattern) as e:
            call()
        if isinstance(e.value, curvflow.CurvflowError) and e.value.status:
            assert e.value.status.startswith("CF_ERR_")


def test_invalid_mesh_statuses(mesh):
    V, F = mesh
    with pytest.raises(curvflow.InvalidMeshError) as e:
        curvflow.flow(V, np.where(F == 5, 999, F), "implicit-mcf")
    assert e.value.status == "CF_ERR_INDEX_RANGE" and e.value.code == -11
    with pytest.raises(curvflow.InvalidMeshError) as e:
        curvflow.flow(np.where(np.arange(len(V))[:, None] == 3, np.nan, V), F, "implicit-mcf")
    assert e.value.status == "CF_ERR_NONFINITE"
    assert isinstance(e.value, ValueError)  # generic handlers keep working


def test_accepted_conversions(mesh):
    """float32 / int coordinates, int64 / uint faces, Fortran order and
    lists are converted; results equal those of the canonical arrays."""
    V, F = mesh
    ref, _ = curvflow.flow(V, F, "implicit-mcf", steps=2)
    for V2, F2 in ((np.asfortranarray(V), F), (V, F.astype(np.int64)), (V, F.astype(np.uint32)),
                   (V.tolist(), F.tolist()), (V.astype(">f8"), F.astype(">i4"))):
        got, _ = curvflow.flow(V2, F2, "implicit-mcf", steps=2)
        assert np.array_equal(got, ref)
    got32, _ = curvflow.flow(V.astype(np.float32), F, "implicit-mcf", steps=2)
    assert np.allclose(got32, ref, atol=1e-6)


def test_inputs_are_not_modified(mesh):
    V, F = mesh
    V0, F0 = V.copy(), F.copy()
    curvflow.flow(V, F, "spin-willmore", steps=2)
    curvflow.edit(V, F, ([0, 1, 2], V[[0, 1, 2]] + 0.1), iterations=2)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)


# ---- methods and parameters ---------------------------------------------------------

def test_unknown_method(mesh):
    with pytest.raises(curvflow.UsageError, match=r"unknown method 'spin-wilmore' \(methods: explicit-mcf, .*"
                                                  r"spin-willmore, stretch-bend-edit\)"):
        curvflow.flow(*mesh, "spin-wilmore")
    with pytest.raises(TypeError, match="method"):
        curvflow.flow(*mesh, 5)


def test_unknown_and_bad_parameters(mesh):
    with pytest.raises(curvflow.UsageError, match=r"parameter 'sigmaa': unknown for method spin-willmore") as e:
        curvflow.flow(*mesh, "spin-willmore", sigmaa=1)
    assert e.value.status == "CF_ERR_INVALID_ARG"
    with pytest.raises(curvflow.UsageError, match=r"time_step"):
        curvflow.flow(*mesh, "spin-willmore", time_step=50.0)  # out of the range [1e-9, 10]
    with pytest.raises(curvflow.UsageError, match=r"boundary"):
        curvflow.flow(*mesh, "spin-willmore", boundary="sideways")
    with pytest.raises(curvflow.UsageError, match=r"mass"):
        curvflow.flow(*mesh, "implicit-mcf", mass=1.5)
    with pytest.raises(TypeError, match=r"parameter sigma: expected a number"):
        curvflow.flow(*mesh, "spin-willmore", sigma=None)
    with pytest.raises(curvflow.UsageError, match=r"parameter sigma of spin-willmore takes a single value"):
        curvflow.flow(*mesh, "spin-willmore", sigma=np.ones(3))
    with pytest.raises(curvflow.UsageError, match=r"steps: expected an integer >= 0, got -1"):
        curvflow.flow(*mesh, "spin-willmore", steps=-1)
    with pytest.raises(curvflow.UsageError, match=r"steps"):
        curvflow.flow(*mesh, "spin-willmore", steps=2.5)
    with pytest.raises(curvflow.UsageError, match=r"boundary_targets / boundary_axis are parameters of spin-willmore"):
        curvflow.flow(*mesh, "implicit-mcf", boundary_targets=mesh[0])
    with pytest.raises(curvflow.UsageError, match=r"boundary_targets needs boundary=prescribed"):
        curvflow.flow(*mesh, "spin-willmore", boundary_targets=mesh[0], boundary="fixed")
    with pytest.raises(curvflow.UsageError, match=r"stretch-bend-edit needs handles"):
        curvflow.flow(*mesh, "stretch-bend-edit")
    with pytest.raises(curvflow.UsageError, match=r"handles / rest_positions are parameters of stretch-bend-edit"):
        curvflow.flow(*mesh, "implicit-mcf", handles=([0], mesh[0][:1]))
    curvflow.check_params("spin-willmore", 0.3, sigma=0.5, boundary="fixed")
    with pytest.raises(curvflow.UsageError, match="sigmaa"):
        curvflow.check_params("spin-willmore", sigmaa=0.5)


def test_method_params_match_cli(cli):
    text = run_cli(cli, "flow", "--method", "spin-willmore", "--list-params").stdout
    params = curvflow.method_params("spin-willmore")
    for name, p in params.items():
        assert "  %s " % name in text and "[%s]" % p["default"] in text
    assert params["boundary"]["choices"] == ["free", "fixed", "prescribed", "cmc"]
    assert params["time_step"]["default"] == "0.5"


def test_bad_handles(mesh, tmp_path):
    V, F = mesh
    with pytest.raises(curvflow.MeshFormatError, match=r"^handles: .*unknown key") as e:
        curvflow.edit(V, F, {"sets": [{"name": "a", "vertices": [1], "fixed": True, "colour": 3}]})
    with pytest.raises(curvflow.CurvflowError, match=r"vertex|index") as e:
        curvflow.edit(V, F, ([0, 500], V[:2]))
    assert e.value.status
    with pytest.raises(curvflow.UsageError, match=r"handles: 2 vertices but 1 targets"):
        curvflow.edit(V, F, ([0, 1], V[:1]))
    with pytest.raises(curvflow.MeshIOError, match=r"nothere\.json"):
        curvflow.edit(V, F, tmp_path / "nothere.json")
    with pytest.raises(TypeError, match=r"handles: expected a JSON file path"):
        curvflow.edit(V, F, 42)
    with pytest.raises(curvflow.UsageError, match=r"energy"):
        curvflow.edit(V, F, ([0], V[:1]), energy="elastic")


# ---- files --------------------------------------------------------------------------

BAD_FILES = [
    ("flipped_face_spot.obj", curvflow.InvalidMeshError, "CF_ERR_ORIENTATION",
     r"flipped_face_spot\.obj: faces 94 and 100: edge \(212, 822\) is traversed in the same direction"),
    ("nan_coordinate_bunny.obj", curvflow.InvalidMeshError, "CF_ERR_NONFINITE",
     r"nan_coordinate_bunny\.obj: line 11: vertex 10 has a non-finite coordinate"),
    ("nonmanifold_edges_beetle.obj", curvflow.InvalidMeshError, "CF_ERR_NONMANIFOLD_EDGE",
     r"nonmanifold_edges_beetle\.obj: face 716: edge \(135, 136\) is shared by 3 faces"),
    ("truncated_spot.obj", curvflow.MeshFormatError, "CF_ERR_TRUNCATED",
     r"truncated_spot\.obj: line 7063: face has 2 vertices"),
]


@pytest.mark.parametrize("name,exc,status,pattern", BAD_FILES, ids=[b[0] for b in BAD_FILES])
def test_shared_bad_files(cli, shared, name, exc, status, pattern):
    path = shared / "bad" / name
    with pytest.raises(exc, match=pattern) as e:
        curvflow.load(path)
    assert e.value.status == status
    # the CLI prints the same message and exits with 2
    proc = run_cli(cli, "info", path, check=False)
    assert proc.returncode == 2 and str(e.value) in proc.stderr


def test_unreadable_and_unknown_files(tmp_path):
    with pytest.raises(curvflow.MeshIOError, match=r"missing\.obj: cannot open") as e:
        curvflow.load(tmp_path / "missing.obj")
    assert isinstance(e.value, OSError)
    (tmp_path / "x.stl").write_text("solid\n")
    with pytest.raises(curvflow.UnsupportedError, match=r"x\.stl"):
        curvflow.load(tmp_path / "x.stl")
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 zebra\n")
    with pytest.raises(curvflow.MeshFormatError, match=r"bad\.obj: line 4"):
        curvflow.load(tmp_path / "bad.obj")
    # validate=False returns what a syntactically fine file holds
    (tmp_path / "flat.obj").write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
    with pytest.raises(curvflow.InvalidMeshError, match=r"flat\.obj: face 0"):
        curvflow.load(tmp_path / "flat.obj")
    V, F, _ = curvflow.load(tmp_path / "flat.obj", validate=False)
    assert V.shape == (3, 3) and F.tolist() == [[0, 1, 2]]
    # a vertex no face uses is dropped as the commands drop it; weld=False keeps it, and the mesh is refused
    (tmp_path / "dup.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\nf 1 2 3\n")
    V, F, extras = curvflow.load(tmp_path / "dup.obj")
    assert V.shape == (3, 3) and extras["unused_vertices_dropped"] == 1
    with pytest.raises(curvflow.InvalidMeshError, match=r"dup\.obj: vertex 3"):
        curvflow.load(tmp_path / "dup.obj", weld=False)
    V, F, _ = curvflow.load(tmp_path / "dup.obj", validate=False, weld=False)
    assert V.shape == (4, 3) and F.tolist() == [[0, 1, 2]]


def test_save_errors(mesh, tmp_path):
    V, F = mesh
    with pytest.raises(curvflow.MeshIOError, match=r"no_dir"):
        curvflow.save(tmp_path / "no_dir" / "x.ply", V, F)
    with pytest.raises(curvflow.UsageError, match=r"field q: expected 162 \(vertices\) or 320 \(faces\) values"):
        curvflow.save(tmp_path / "x.ply", V, F, fields={"q": np.zeros(5)})
    with pytest.raises(curvflow.UsageError, match=r"field"):
        curvflow.save(tmp_path / "x.ply", V, F, fields={"x": np.zeros(len(V))})  # reserved name
    with pytest.raises(curvflow.UsageError, match=r"uv has 3 rows but V has 162 vertices"):
        curvflow.save(tmp_path / "x.ply", V, F, uv=np.zeros((3, 2)))
    with pytest.raises(curvflow.InvalidMeshError, match="NaN"):
        curvflow.save(tmp_path / "x.ply", np.where(V == V[4, 0], np.nan, V), F)
    assert list(tmp_path.iterdir()) == []  # nothing half-written


# ---- numerical failures -------------------------------------------------------------

def test_numerical_failure_keeps_last_good_state(cli, meshes, tmp_path):
    """An unstable explicit step: NumericalError with the library's message,
    .last_positions equal to the last good state the CLI writes (exit 3),
    and .log up to it."""
    out = tmp_path / "last.obj"
    proc = run_cli(cli, "flow", meshes["bumpy"], "-o", out, "--method", "explicit-mcf", "--time-step", "0.45",
                   "--steps", "40", "-q", check=False)
    assert proc.returncode == 3
    V, F, _ = curvflow.load(meshes["bumpy"])
    with pytest.raises(curvflow.NumericalError, match=r"^iteration (\d+): explicit-mcf: energy rose") as e:
        curvflow.flow(V, F, "explicit-mcf", time_step=0.45, steps=40)
    err = e.value
    assert err.status == "CF_ERR_NUMERICAL" and isinstance(err, ArithmeticError)
    failed = int(str(err).split(":")[0].split()[1])
    assert err.log[-1]["iteration"] == failed - 1 and len(err.log) == failed
    assert np.array_equal(err.last_positions, curvflow.load(out)[0])
    assert str(err) in proc.stderr
