"""A scene of several objects (one mesh of several connected components)
through the Python API: spin-willmore flows each object as its own flow
(docs/spin.md, "Several connected components"), so each one's result is the
one it gets alone, bit for bit, and the log's W is the sum; before session 28
all objects but one shrank to a point."""
import numpy as np

import curvflow


def _scene(parts, shift=4.0):
    """The parts (V, F) side by side along x, in one mesh."""
    Vs, Fs, offset = [], [], 0
    for k, (V, F) in enumerate(parts):
        Vs.append(V + np.array([shift * k, 0.0, 0.0]))
        Fs.append(F + offset)
        offset += len(V)
    return np.vstack(Vs), np.vstack(Fs).astype(np.int32)


def _area(X, F):
    e1, e2 = X[F[:, 1]] - X[F[:, 0]], X[F[:, 2]] - X[F[:, 0]]
    return 0.5 * np.linalg.norm(np.cross(e1, e2), axis=1).sum()


def test_scene_flows_each_object_as_alone(meshes):
    bumpy = curvflow.load(meshes["bumpy"])[:2]
    torus = curvflow.load(meshes["torus"])[:2]
    V, F = _scene([bumpy, torus])
    out, log = curvflow.flow(V, F, "spin-willmore", steps=5)
    n = len(bumpy[0])
    # each object alone, where the scene has it (the torus at x + 4)
    moved_torus = torus[0] + np.array([4.0, 0.0, 0.0])
    alone_b, log_b = curvflow.flow(bumpy[0], bumpy[1], "spin-willmore", steps=5)
    alone_t, log_t = curvflow.flow(moved_torus, torus[1], "spin-willmore", steps=5)
    assert np.array_equal(out[:n], alone_b)
    assert np.array_equal(out[n:], alone_t)
    assert log[-1]["energy"] == log_b[-1]["energy"] + log_t[-1]["energy"]
    # every object keeps its own area (`normalize`, per object)
    assert abs(_area(out[:n], bumpy[1]) / _area(bumpy[0], bumpy[1]) - 1.0) < 1e-9
    assert abs(_area(out[n:], torus[1]) / _area(moved_torus, torus[1]) - 1.0) < 1e-9
