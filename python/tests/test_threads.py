"""CURVFLOW_THREADS, the solver threads (cf_context_set_threads), as the
Python package and the CLI read it: unset means the library's default (one
thread); a value other than an integer 0..1024 is a UsageError; 0 and 2
give the default's result up to rounding, and each front end equals the
other under the same value."""
import os
import subprocess

import numpy as np
import pytest

import curvflow


@pytest.mark.parametrize("value", ["abc", "-1", " 2", "1025", "", "2.5"])
def test_bad_value_is_a_usage_error(meshes, monkeypatch, value):
    V, F, _ = curvflow.load(meshes["bumpy"])
    monkeypatch.setenv("CURVFLOW_THREADS", value)
    with pytest.raises(curvflow.UsageError, match="CURVFLOW_THREADS must be an integer from 0 to 1024"):
        curvflow.flow(V, F, "spin-willmore", steps=1)


@pytest.mark.parametrize("value", ["0", "2"])
def test_values_agree_with_the_default_and_the_cli(cli, meshes, monkeypatch, tmp_path, value):
    V, F, _ = curvflow.load(meshes["bumpy"])
    monkeypatch.delenv("CURVFLOW_THREADS", raising=False)
    default, _ = curvflow.flow(V, F, "spin-willmore", steps=3)
    monkeypatch.setenv("CURVFLOW_THREADS", value)
    got, _ = curvflow.flow(V, F, "spin-willmore", steps=3)
    assert np.abs(got - default).max() <= 1e-9
    out = tmp_path / "out.obj"
    env = dict(os.environ, CURVFLOW_THREADS=value)
    subprocess.run([str(cli), "flow", str(meshes["bumpy"]), "-o", str(out), "--method", "spin-willmore",
                    "--steps", "3", "-q"], check=True, env=env)
    assert np.array_equal(curvflow.load(out)[0], got)


def test_cli_refuses_a_bad_value(cli, meshes):
    env = dict(os.environ, CURVFLOW_THREADS="x")
    r = subprocess.run([str(cli), "info", str(meshes["bumpy"])], env=env, capture_output=True, text=True)
    assert r.returncode == 1
    assert r.stderr == "curvflow: CURVFLOW_THREADS must be an integer from 0 to 1024, got 'x'\n"
