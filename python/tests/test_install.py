"""The documented local install works without PyPI: a venv made with
Debian's /usr/bin/python3 -m venv --system-site-packages (numpy from
python3-numpy), `pip install --no-build-isolation --no-index ./python`
(Debian's setuptools + wheel), and the installed package runs from
anywhere with the library copied into it, without the checkout's
environment variables."""
import os
import shutil
import subprocess
import venv

import pytest

from conftest import BUILD_DIR, ROOT


def test_pip_install_into_venv(tmp_path):
    pytest.importorskip("ensurepip", reason="SKIP: python3-venv (ensurepip) is not installed")
    pytest.importorskip("wheel", reason="SKIP: Debian's python3-wheel is not installed")
    # build from a copy, so that concurrent runs do not share python/build
    src = tmp_path / "src"
    shutil.copytree(ROOT / "python", src, ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__",
                                                                       ".pytest_cache", "tests"))
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(system_site_packages=True, with_pip=True).create(env_dir)
    py = str(env_dir / "bin" / "python")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "BUILD_DIR", "CURVFLOW_LIB_DIR")}
    pip = subprocess.run([py, "-m", "pip", "install", "--no-build-isolation", "--no-index", str(src)],
                         capture_output=True, text=True, env=dict(env, CURVFLOW_LIB_DIR=str(BUILD_DIR)))
    assert pip.returncode == 0, pip.stdout + pip.stderr
    check = ("import curvflow, numpy as np; V, F, _ = curvflow.load(%r); W, log = curvflow.flow(V, F, "
             "'spin-willmore', steps=2); print(curvflow.__file__); print(curvflow.library_path()); "
             "print(len(log))" % str(tmp_path / "m.obj"))
    subprocess.run([str(BUILD_DIR / "curvflow"), "generate", "icosphere", "-o", str(tmp_path / "m.obj")],
                   check=True, capture_output=True)
    run = subprocess.run([py, "-c", check], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    module, lib, steps = run.stdout.split()
    site = str(env_dir / "lib")
    assert module.startswith(site) and lib.startswith(site) and lib.endswith("libcurvflow.so.0")
    assert steps == "3"
    # the batch entry point is installed too
    assert (env_dir / "bin" / "curvflow-batch").is_file()
