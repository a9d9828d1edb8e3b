"""Seams (docs/io.md): a mesh file whose boundary vertices lie on others, as
exporters write texture seams and unshared triangles, is welded by load()
and by every command, and flows as the closed surface it describes; the
vertices no face uses are dropped the same way ("Unused vertices");
--no-weld / weld=False keep the file's vertices; files numbered for the
file's vertices are refused once the weld renumbered them."""
import json

import numpy as np
import pytest

import curvflow
from conftest import run_cli


def _seam_copy(V, F):
    """V, F cut along x = 0: the vertices used on both sides (cut) get
    copies, appended after the originals and used by the faces with x > 0.
    Returns the cut's V, F and the vertices copied, in the copies' order."""
    right = V[F].mean(axis=1)[:, 0] > 0
    both = np.zeros(len(V), dtype=int)
    np.add.at(both, F[right].ravel(), 1)
    left_used = np.zeros(len(V), dtype=bool)
    left_used[F[~right].ravel()] = True
    cut = np.flatnonzero((both > 0) & left_used)
    index = np.arange(len(V))
    index[cut] = len(V) + np.arange(len(cut))
    F2 = F.copy()
    F2[right] = index[F[right]]
    return np.vstack([V, V[cut]]), F2, cut


def _write_obj(path, V, F):
    with open(path, "w") as fp:
        fp.writelines("v %.17g %.17g %.17g\n" % tuple(v) for v in V)
        fp.writelines("f %d %d %d\n" % tuple(f + 1) for f in F)


def test_seam_flows_as_the_closed_surface(cli, meshes, tmp_path):
    V, F, _ = curvflow.load(meshes["bumpy"], weld=False)
    V2, F2, cut = _seam_copy(V, F)
    copies = len(cut)
    assert copies > 20
    seam, plain = tmp_path / "seam.obj", tmp_path / "plain.obj"
    _write_obj(seam, V2, F2)
    _write_obj(plain, V, F)
    # as the file says: two boundary loops; what the commands make of it: closed
    js = json.loads(run_cli(cli, "info", seam, "--json").stdout)
    assert js["boundary_loops"] == 2 and js["vertices"] == len(V2)
    assert js["seams"] == {"unused_vertices": 0, "coincident_boundary_vertices": 2 * copies, "positions": copies,
                           "welded_vertices": len(V), "welded_boundary_loops": 0, "welded_genus": 0,
                           "refused": None}
    assert curvflow.info(seam)["seams"] == js["seams"]
    # the copies come last, so the welded file is the plain one vertex for vertex
    Vw, Fw, ex = curvflow.load(seam)
    assert np.array_equal(Vw, V) and np.array_equal(Fw, F)
    assert ex["weld"]["welded"] and ex["weld"]["removed"] == copies and ex["weld"]["refused"] is None
    assert curvflow.load(seam, weld=False)[0].shape == V2.shape
    proc = run_cli(cli, "flow", seam, "-o", tmp_path / "a.obj", "--method", "spin-willmore", "-n", "3", "-q")
    assert "welded %d seam vertices" % copies in proc.stderr and "%d vertices instead of %d" % (len(V), len(V2)) \
        in proc.stderr
    run_cli(cli, "flow", plain, "-o", tmp_path / "b.obj", "--method", "spin-willmore", "-n", "3", "-q")
    assert (tmp_path / "a.obj").read_bytes() == (tmp_path / "b.obj").read_bytes()
    # --no-weld: the cut is a free boundary, and the flow opens it
    run_cli(cli, "flow", seam, "-o", tmp_path / "c.obj", "--method", "spin-willmore", "-n", "3", "-q", "--no-weld")
    Vc, Fc, _ = curvflow.load(tmp_path / "c.obj", weld=False)
    assert len(Vc) == len(V2)
    gap = np.linalg.norm(Vc[len(V):] - Vc[cut], axis=1)
    assert gap.max() > 1e-3


def test_soup_welds_and_files_for_the_file_are_refused(cli, meshes, tmp_path):
    V, F, _ = curvflow.load(meshes["icosphere"], weld=False)
    soup = tmp_path / "soup.obj"
    _write_obj(soup, V[F.ravel()], np.arange(3 * len(F)).reshape(-1, 3))
    info = curvflow.info(soup)
    assert info["boundary_loops"] == len(F) and info["seams"]["welded_vertices"] == len(V)
    assert info["seams"]["welded_boundary_loops"] == 0
    run_cli(cli, "flow", soup, "-o", tmp_path / "s.obj", "--method", "conformal-mcf", "-n", "2", "-q")
    run_cli(cli, "flow", meshes["icosphere"], "-o", tmp_path / "i.obj", "--method", "conformal-mcf", "-n", "2", "-q")
    ws, wi = (curvflow.info(tmp_path / n)["willmore_over_4pi"] for n in ("s.obj", "i.obj"))
    assert abs(ws - wi) < 1e-9 * wi
    # a rho file of the soup's 3 x faces values numbers the file's vertices
    rho = tmp_path / "rho.txt"
    rho.write_text("0.1\n" * (3 * len(F)))
    proc = run_cli(cli, "spin", soup, "--rho", rho, "-o", tmp_path / "r.obj", check=False)
    assert proc.returncode == 2 and "seams were welded (%d vertices joined)" % (3 * len(F) - len(V)) in proc.stderr
    assert not (tmp_path / "r.obj").exists()
    run_cli(cli, "spin", soup, "--rho", rho, "-o", tmp_path / "r.obj", "--no-weld")
    # so does a handle file
    handles = tmp_path / "h.json"
    handles.write_text(json.dumps({"sets": [{"name": "base", "vertices": [0, 1, 2], "fixed": True}]}))
    proc = run_cli(cli, "edit", soup, "--handles", handles, "-o", tmp_path / "e.obj", "-n", "2", check=False)
    assert proc.returncode == 2 and "--handles %s: " % handles in proc.stderr and "--no-weld" in proc.stderr
    assert not (tmp_path / "e.obj").exists()


def test_weld_arrays(meshes):
    """weld() on arrays is load()'s weld: the soup's arrays give the welded
    file's; a bow tie is refused with the reason; bad indices raise."""
    V, F, _ = curvflow.load(meshes["icosphere"], weld=False)
    Vs, Fs = V[F.ravel()], np.arange(3 * len(F)).reshape(-1, 3)
    V2, F2, index, report = curvflow.weld(Vs, Fs)
    assert report["welded"] and report["vertices"] == len(V) and report["removed"] == 3 * len(F) - len(V)
    assert V2.shape == V.shape and F2.dtype == np.int32 and np.array_equal(F2, index[Fs])
    assert np.array_equal(V2[F2], Vs[Fs])  # every corner where it was
    assert curvflow.info(V2, F2)["boundary_loops"] == 0 and curvflow.info(V2, F2)["genus"] == 0
    bowtie = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 0], [-1, 0, 0], [0, -1, 0]], dtype=float)
    V3, F3, index3, report3 = curvflow.weld(bowtie, [[0, 1, 2], [3, 4, 5]])
    assert not report3["welded"] and report3["coincident_boundary_vertices"] == 2
    assert "separate fans" in report3["refused"] and np.array_equal(index3, np.arange(6)) and len(V3) == 6
    with pytest.raises(curvflow.InvalidMeshError, match="face 1: vertex index 9 out of range"):
        curvflow.weld(bowtie, [[0, 1, 2], [3, 4, 9]])


def test_unused_vertices_are_dropped(cli, meshes, tmp_path):
    """A file with vertices no face uses (a scan's stray points, an editor's
    deleted faces): dropped by load() and the commands, which then run; kept,
    and refused, with --no-weld / weld=False; files numbering the file's
    vertices are refused after the drop."""
    V, F, _ = curvflow.load(meshes["icosphere"], weld=False)
    stray = np.array([[5.0, 5.0, 5.0], [-5.0, 0.0, 0.0]])
    # one stray vertex after the first, one at the end: the faces renumbered
    V2 = np.vstack([V[:1], stray[:1], V[1:], stray[1:]])
    F2 = np.where(F >= 1, F + 1, F)
    path = tmp_path / "stray.obj"
    _write_obj(path, V2, F2)
    proc = run_cli(cli, "info", path, "--json", check=False)  # the file as it is: an invalid mesh (exit 2)
    js = json.loads(proc.stdout)
    assert proc.returncode == 2 and js["vertices"] == len(V2) and not js["validation"]["valid"]
    assert js["validation"]["unreferenced_vertices"] == 2 and js["seams"]["unused_vertices"] == 2
    assert curvflow.info(path)["seams"] == js["seams"]
    Vd, Fd, ex = curvflow.load(path)
    assert np.array_equal(Vd, V) and np.array_equal(Fd, F) and ex["unused_vertices_dropped"] == 2
    with pytest.raises(curvflow.InvalidMeshError, match="vertex 1 is not used by any face"):
        curvflow.load(path, weld=False)
    assert curvflow.load(path, weld=False, validate=False)[0].shape == V2.shape
    proc = run_cli(cli, "flow", path, "-o", tmp_path / "a.obj", "--method", "implicit-mcf", "-n", "2", "-q")
    assert "dropped 2 vertices that no face uses: %d vertices instead of %d" % (len(V), len(V2)) in proc.stderr
    run_cli(cli, "flow", meshes["icosphere"], "-o", tmp_path / "b.obj", "--method", "implicit-mcf", "-n", "2", "-q")
    assert (tmp_path / "a.obj").read_bytes() == (tmp_path / "b.obj").read_bytes()
    proc = run_cli(cli, "flow", path, "-o", tmp_path / "c.obj", "--method", "implicit-mcf", "-n", "2", "--no-weld",
                   check=False)
    assert proc.returncode == 2 and "vertex 1 is not used by any face" in proc.stderr
    rho = tmp_path / "rho.txt"
    rho.write_text("0.1\n" * len(V2))
    proc = run_cli(cli, "spin", path, "--rho", rho, "-o", tmp_path / "r.obj", check=False)
    assert proc.returncode == 2 and "unused vertices were dropped (2)" in proc.stderr and "--no-weld" in proc.stderr
    assert not (tmp_path / "r.obj").exists()
