"""curvflow.loop_subdivide: counts, what is kept, planes stay planes, and bad input.

One level maps (V, E, F) to (V + E, 4F) and keeps the Euler characteristic;
the first len(V) vertices are the input's, moved by the even rule; a flat
open grid stays in its plane (the Loop and boundary rules are affine
combinations); the result of two levels on the torus is a valid mesh of the
same genus. Levels outside 1..10 and a non-manifold input are refused.
"""
import numpy as np
import pytest

import curvflow


def _edge_count(F):
    edges = np.sort(np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]), axis=1)
    return len(np.unique(edges, axis=0))


def test_counts_and_euler_characteristic(meshes):
    V, F, _ = curvflow.load(meshes["icosphere"])
    V1, F1 = curvflow.loop_subdivide(V, F)
    assert V1.shape == (len(V) + _edge_count(F), 3)
    assert F1.shape == (4 * len(F), 3)
    assert V1.dtype == np.float64 and F1.dtype == np.int32
    info = curvflow.info(V1, F1)
    assert info["validation"]["valid"] and info["euler_characteristic"] == 2
    # every vertex of the icosphere moves toward the centre (the even rule averages neighbours on a sphere)
    r0, r1 = np.linalg.norm(V, axis=1), np.linalg.norm(V1[:len(V)], axis=1)
    assert np.all(r1 < r0)


def test_plane_stays_plane_with_boundary(meshes):
    V, F, _ = curvflow.load(meshes["grid"])
    assert np.all(V[:, 2] == 0.0)
    V2, F2 = curvflow.loop_subdivide(V, F, levels=2)
    assert F2.shape[0] == 16 * len(F)
    assert np.abs(V2[:, 2]).max() == 0.0
    # the square's corners are kept by the boundary rules: the bounding box is unchanged
    assert np.allclose(V2[:, :2].min(0), V[:, :2].min(0)) and np.allclose(V2[:, :2].max(0), V[:, :2].max(0))


def test_genus_kept(meshes):
    V, F, _ = curvflow.load(meshes["torus"])
    V2, F2 = curvflow.loop_subdivide(V, F, 2)
    info = curvflow.info(V2, F2)
    assert info["validation"]["valid"] and info["genus"] == 1


def test_bad_input(meshes):
    V, F, _ = curvflow.load(meshes["icosphere"])
    with pytest.raises(curvflow.CurvflowError, match="level"):
        curvflow.loop_subdivide(V, F, 0)
    with pytest.raises(TypeError):
        curvflow.loop_subdivide(V, F, 1.5)
    bad = np.vstack([F, [[F[0, 0], F[0, 1], len(V) - 1]]]).astype(np.int32)  # a third face on one edge
    with pytest.raises(curvflow.InvalidMeshError):
        curvflow.loop_subdivide(V, bad)
