#!/usr/bin/env python3
"""Flows on generated meshes of the kinds issue 13 checks outside ../shared:
a knotted tube (genus 1), marching-tetrahedra plates of genus 1-5 (slivers down
to about 0.1 degrees, staircase noise), a sphere with 7 holes and a disk; with
--subdivided, cow_3k and dino_4k Loop-subdivided twice (curvflow.loop_subdivide);
with --stretched, spot_3k stretched 5x and 10x along y and an icosphere
stretched 8x (elongated shapes, docs/spin.md "Elongated shapes"); with --tubes,
14 more knotted tubes (docs/spin.md, "The period tolerance on knotted tubes");
with --mesh, a user's own mesh files (--no-generated leaves out the default
generated ones).

    BUILD_DIR=build python3 bench/bench_unseen_kinds.py [--curvflow PATH] [--steps N] [--keep DIR]
        [--subdivided ../shared/meshes] [--stretched ../shared/meshes] [--tubes]
        [--mesh PATH ...] [--no-generated] [--param KEY=VALUE ...] [METHOD ...]

Writes the meshes (to a temporary directory, or DIR), runs every METHOD
(default: spin-willmore and conformal-mcf) with its defaults for N steps
(default 10) through the CLI and prints one TSV row per mesh x method: exit
status, W/4pi before and after, the number of steps that raised W,
area-weighted mean and max quasi-conformal error against the input, smallest
angle, whole-process ms per step. Nothing
is asserted (docs/spin.md, "Meshes of the unseen kinds"). Needs numpy and the
built library (the Python package's load / save / info / compare /
loop_subdivide; BUILD_DIR,
default build/).
"""
import argparse
import math
import os
import pathlib
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python"))
BUILD = pathlib.Path(os.environ.get("BUILD_DIR") or ROOT / "build").resolve()
os.environ.setdefault("CURVFLOW_LIB_DIR", str(BUILD))

# curvflow before numpy: the package picks OpenBLAS's kernels only if it is
# loaded first (docs/python.md), and the CLI runs timed here inherit them
import curvflow  # noqa: E402
import numpy as np  # noqa: E402


def trefoil(t):
    return np.stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)], 1)


def figure_eight(t):
    return np.stack([(2 + np.cos(2 * t)) * np.cos(3 * t), (2 + np.cos(2 * t)) * np.sin(3 * t), np.sin(4 * t)], 1)


def torus_knot_2_5(t):
    return np.stack([(2 + np.cos(5 * t)) * np.cos(2 * t), (2 + np.cos(5 * t)) * np.sin(2 * t), -np.sin(5 * t)], 1)


def knotted_tube(n_along=240, n_around=14, mean=0.35, amplitude=0.1, centre_line=trefoil):
    """Tube around a knot (trefoil by default), radius mean + amplitude sin 5t
    (five thick and thin stretches), parallel-transport frame closed up by
    spreading its holonomy."""
    t = np.linspace(0.0, 2.0 * np.pi, n_along, endpoint=False)
    centre = centre_line(t)
    tangent = np.roll(centre, -1, 0) - np.roll(centre, 1, 0)
    tangent /= np.linalg.norm(tangent, axis=1)[:, None]
    normal = np.zeros_like(tangent)
    seed = np.array([0.3, 0.5, 0.8])
    normal[0] = seed - tangent[0] * (seed @ tangent[0])
    normal[0] /= np.linalg.norm(normal[0])
    for i in range(1, n_along):
        n = normal[i - 1] - tangent[i] * (normal[i - 1] @ tangent[i])
        normal[i] = n / np.linalg.norm(n)
    binormal = np.cross(tangent, normal)
    last = normal[-1] - tangent[0] * (normal[-1] @ tangent[0])
    holonomy = math.atan2(last @ binormal[0], last @ normal[0])
    phi = np.linspace(0.0, 2.0 * np.pi, n_around, endpoint=False)
    radius = mean + amplitude * np.sin(5 * t)
    vertices = []
    for i in range(n_along):
        angle = phi - holonomy * i / n_along
        ring = centre[i] + radius[i] * (np.cos(angle)[:, None] * normal[i] + np.sin(angle)[:, None] * binormal[i])
        vertices.extend(ring)
    faces = []
    for i in range(n_along):
        i2 = (i + 1) % n_along
        for j in range(n_around):
            j2 = (j + 1) % n_around
            a, b, c, d = i * n_around + j, i * n_around + j2, i2 * n_around + j, i2 * n_around + j2
            faces += [(a, b, c), (b, d, c)]
    return np.array(vertices), np.array(faces)


def marching_tetrahedra(values, axes):
    """Zero set of values (> 0 outside) on the grid axes, six tetrahedra per
    cube; one vertex per crossed grid edge, so the result is closed and
    manifold when no grid value is zero. Faces point toward positive values."""
    values = np.where(np.abs(values) < 1e-12, 1e-12, values)
    corner = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 1)]
    tets = [(0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)]
    index, vertices, faces = {}, [], []

    def point(p):
        return np.array([axes[k][p[k]] for k in range(3)])

    def crossing(p, q):
        key = (p, q) if p < q else (q, p)
        if key not in index:
            s = values[p] / (values[p] - values[q])
            vertices.append(point(p) + s * (point(q) - point(p)))
            index[key] = len(vertices) - 1
        return index[key]

    def oriented(tri, toward):
        a, b, c = (vertices[k] for k in tri)
        return tri if np.cross(b - a, c - a) @ (toward - a) > 0 else tri[::-1]

    shape = values.shape
    outside = values > 0
    for i in range(shape[0] - 1):
        for j in range(shape[1] - 1):
            for k in range(shape[2] - 1):
                cube = [(i + o[0], j + o[1], k + o[2]) for o in corner]
                flags = [outside[p] for p in cube]
                if all(flags) or not any(flags):
                    continue
                for tet in tets:
                    p = [cube[m] for m in tet]
                    out = [m for m in range(4) if outside[p[m]]]
                    inn = [m for m in range(4) if not outside[p[m]]]
                    if len(out) in (1, 3):
                        lone = out[0] if len(out) == 1 else inn[0]
                        tri = [crossing(p[lone], p[m]) for m in range(4) if m != lone]
                        # the normal points to the outside corner(s)
                        target = point(p[lone]) if len(out) == 1 else np.mean([point(p[m]) for m in out], 0)
                        faces.append(oriented(tri, target))
                    elif len(out) == 2:
                        a, b = out
                        c, d = inn
                        quad = [crossing(p[a], p[c]), crossing(p[a], p[d]), crossing(p[b], p[d]), crossing(p[b], p[c])]
                        target = (point(p[a]) + point(p[b])) / 2
                        first = oriented([quad[0], quad[1], quad[2]], target)
                        second = oriented([quad[0], quad[2], quad[3]], target)
                        faces += [first, second]
    return np.array(vertices), np.array(faces)


def holed_plate(genus):
    """A rounded slab of thickness 0.7 with genus round holes of radius 0.45."""
    centres = np.linspace(-(genus - 1), genus - 1, genus) if genus > 1 else np.array([0.0])
    nx = int(22 * (genus + 0.6) / 1.6) + 1
    axes = [np.linspace(-genus - 0.6, genus + 0.6, nx), np.linspace(-1.6, 1.6, 23), np.linspace(-0.6, 0.6, 10)]
    x, y, z = np.meshgrid(*axes, indexing="ij")
    flat = np.hypot(np.maximum(np.abs(x) - genus, 0.0), np.maximum(np.abs(y) - 1.0, 0.0))
    d = np.hypot(flat, z) - 0.35
    for c in centres:
        d = np.maximum(d, 0.45 - np.hypot(x - c, y))
    return marching_tetrahedra(d, axes)


def generated_sphere(cli, path):
    subprocess.run([cli, "generate", "bumpy-sphere", "--subdivisions", "4", "--amplitude", "0.1", "-o", path, "-f"],
                   check=True, capture_output=True)
    vertices, faces, _ = curvflow.load(path)
    return vertices, faces


# --tubes: the knotted tubes of docs/spin.md ("Long tubes", "The period
# tolerance on knotted tubes"): name, rings, vertices a ring, mean radius,
# amplitude, centre line
TUBES = [("tube_trefoil_480x28", 480, 28, 0.35, 0.1, trefoil), ("tube_trefoil_360x20", 360, 20, 0.35, 0.1, trefoil),
         ("tube_trefoil_120x10", 120, 10, 0.35, 0.1, trefoil), ("tube_trefoil_35pm05", 240, 14, 0.35, 0.05, trefoil),
         ("tube_trefoil_35pm15", 240, 14, 0.35, 0.15, trefoil), ("tube_trefoil_35", 240, 14, 0.35, 0.0, trefoil),
         ("tube_trefoil_30pm10", 240, 14, 0.30, 0.1, trefoil), ("tube_trefoil_40pm10", 240, 14, 0.40, 0.1, trefoil),
         ("tube_trefoil_25", 240, 14, 0.25, 0.0, trefoil), ("tube_trefoil_50", 240, 14, 0.50, 0.0, trefoil),
         ("tube_figure_eight_35pm10", 300, 14, 0.35, 0.1, figure_eight),
         ("tube_figure_eight_30", 300, 14, 0.30, 0.0, figure_eight),
         ("tube_2_5_30pm10", 300, 14, 0.30, 0.1, torus_knot_2_5), ("tube_2_5_25", 300, 12, 0.25, 0.0, torus_knot_2_5)]


def cut_holes(vertices, faces, count, angular_radius):
    """Faces whose direction lies within angular_radius of one of count
    directions spread over the sphere are removed (unused vertices too)."""
    k = np.arange(count) + 0.5
    theta = np.arccos(1 - 2 * k / count)
    phi = np.pi * (1 + 5 ** 0.5) * k
    centres = np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], 1)
    direction = vertices[faces].mean(1)
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    keep = np.all(direction @ centres.T < math.cos(angular_radius), axis=1)
    faces = faces[keep]
    used = np.unique(faces)
    remap = -np.ones(len(vertices), dtype=int)
    remap[used] = np.arange(len(used))
    return vertices[used], remap[faces]


def run(cli, mesh, method, steps, out_dir, params=()):
    base = os.path.splitext(os.path.basename(mesh))[0]
    out = os.path.join(out_dir, "%s.%s.obj" % (base, method))
    log = os.path.join(out_dir, "%s.%s.jsonl" % (base, method))
    for path in (out, log):
        if os.path.exists(path):
            os.remove(path)
    start = time.time()
    command = [cli, "flow", mesh, "-o", out, "--method", method, "--steps", str(steps), "-q", "-f", "--log", log]
    for param in params:
        command += ["-p", param]
    proc = subprocess.run(command, capture_output=True, text=True)
    ms = 1000.0 * (time.time() - start) / steps
    # W/4pi from the flow's log where the method reports it (boundary
    # meshes included: interior vertices, as the method's W), else from
    # info (closed meshes only)
    logged = [entry["terms"]["W/4pi"] for entry in curvflow.read_log(log)
              if "W/4pi" in (entry.get("terms") or {})] if os.path.exists(log) else []
    # (an invalid or open mesh has no W in info)
    w0 = logged[0] if logged else curvflow.info(mesh).get("willmore_over_4pi")
    if proc.returncode != 0:
        print("%s %s: exit %d: %s" % (base, method, proc.returncode, (proc.stderr.strip().splitlines() or [""])[0]),
              file=sys.stderr)
    row = [base, method, str(proc.returncode), "%.3f" % w0 if w0 is not None else "-"]
    # issue 13 asks W non-increasing at every step (rounding allowed)
    rises = sum(1 for a, b in zip(logged, logged[1:]) if b > a * (1.0 + 1e-9))
    if os.path.exists(out):
        after = curvflow.info(out)
        w1 = logged[-1] if logged else after.get("willmore_over_4pi")
        v0, faces, _ = curvflow.load(mesh)
        v1, _, _ = curvflow.load(out, validate=False)
        q = curvflow.compare(v0, v1, faces)["quasi_conformal_error"]
        row += ["%.3f" % w1 if w1 is not None else "-", str(rises) if logged else "-", "%.3f" % q["mean"],
                "%.3g" % q["max"], "%.2f" % after["angles"]["min_degrees"]]
    else:
        row += ["-"] * 5
    row.append("%.0f" % ms)
    print("\t".join(row), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--curvflow", default=str(BUILD / "curvflow"))
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--keep", help="write the meshes and results here (kept)")
    parser.add_argument("--subdivided", metavar="MESH_DIR",
                        help="also cow_3k and dino_4k from MESH_DIR (e.g. ../shared/meshes), Loop-subdivided twice "
                             "(46k and 63k vertices, closed: the 50k-vertex kind)")
    parser.add_argument("--stretched", metavar="MESH_DIR",
                        help="also spot_3k from MESH_DIR stretched 5x and 10x along y, and an icosphere stretched 8x")
    parser.add_argument("--tubes", action="store_true",
                        help="also 14 more knotted tubes: trefoils of other radii and resolutions, figure-eight "
                             "and (2,5) torus knots")
    parser.add_argument("--mesh", action="append", default=[], metavar="PATH",
                        help="also this mesh file (repeatable): a user's own mesh in the same table")
    parser.add_argument("--no-generated", action="store_true",
                        help="leave out the default generated meshes (knot, plates, holed sphere, disk)")
    parser.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                        help="a method parameter for every run (repeatable), e.g. period_tolerance=1e-3")
    parser.add_argument("methods", nargs="*", default=["spin-willmore", "conformal-mcf"])
    args = parser.parse_args()
    if not os.path.exists(args.curvflow):
        sys.exit("no curvflow binary at %s (build first, or --curvflow PATH)" % args.curvflow)
    with tempfile.TemporaryDirectory() as tmp:
        out_dir = args.keep or tmp
        os.makedirs(out_dir, exist_ok=True)
        meshes = []

        def add(name, vertices, faces):
            path = os.path.join(out_dir, name + ".obj")
            curvflow.save(path, vertices, faces)
            meshes.append(path)

        if not args.no_generated:
            add("knot", *knotted_tube())
            for genus in (1, 2, 3, 4, 5):
                add("plate_genus%d" % genus, *holed_plate(genus))
            sphere = generated_sphere(args.curvflow, os.path.join(out_dir, "sphere_source.obj"))
            add("sphere_7_holes", *cut_holes(*sphere, 7, 0.25))
            add("disk_cap", *cut_holes(*sphere, 1, 1.3))
        for name, rings, around, mean, amplitude, centre_line in TUBES if args.tubes else ():
            add(name, *knotted_tube(rings, around, mean, amplitude, centre_line))
        for name in ("cow_3k", "dino_4k") if args.subdivided else ():
            source = os.path.join(args.subdivided, name + ".obj")
            if not os.path.exists(source):
                print("skip %s: %s is absent" % (name, source), file=sys.stderr)
                continue
            vertices, faces, _ = curvflow.load(source)
            add(name + "_loop2", *curvflow.loop_subdivide(vertices, faces, 2))
        if args.stretched:
            ico = os.path.join(out_dir, "icosphere_source.obj")
            subprocess.run([args.curvflow, "generate", "icosphere", "--subdivisions", "4", "-o", ico, "-f"],
                           check=True, capture_output=True)
            vertices, faces, _ = curvflow.load(ico)
            add("icosphere_y8", vertices * np.array([1.0, 8.0, 1.0]), faces)
            source = os.path.join(args.stretched, "spot_3k.obj")
            if os.path.exists(source):
                vertices, faces, _ = curvflow.load(source)
                for factor in (5, 10):
                    add("spot_3k_y%d" % factor, vertices * np.array([1.0, factor, 1.0]), faces)
            else:
                print("skip spot_3k: %s is absent" % source, file=sys.stderr)
        meshes += args.mesh
        print("mesh\tmethod\texit\tW0/4pi\tW/4pi\tW_rises\tQ_mean\tQ_max\tmin_angle\tms_per_step")
        for mesh in meshes:
            for method in args.methods:
                run(args.curvflow, mesh, method, args.steps, out_dir, args.param)


if __name__ == "__main__":
    main()
