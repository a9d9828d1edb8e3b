"""Fixtures of the curvflow Python tests.

The package under test is the checkout's (python/), the library and the CLI
those of one build directory ($BUILD_DIR, else <checkout>/build), so that a
bit-for-bit comparison between Python and the CLI compares one build.
Tests needing the shared meshes ($CURVFLOW_SHARED_DIR/meshes or
../shared/meshes) skip with the reason shown when they are absent.
"""
import json
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python"))

BUILD_DIR = pathlib.Path(os.environ.get("BUILD_DIR") or ROOT / "build").resolve()
if not os.environ.get("CURVFLOW_LIB_DIR"):
    # the library of the same build as the CLI
    os.environ["CURVFLOW_LIB_DIR"] = str(BUILD_DIR)
os.environ.setdefault("OMP_THREAD_LIMIT", "1")

import curvflow  # noqa: E402


def shared_meshes():
    base = os.environ.get("CURVFLOW_SHARED_DIR")
    d = pathlib.Path(base) / "meshes" if base else ROOT.parent / "shared" / "meshes"
    return d if d.is_dir() else None


@pytest.fixture(scope="session")
def cli():
    exe = BUILD_DIR / "curvflow"
    if not exe.is_file():
        pytest.fail("no curvflow executable in %s (build first or set BUILD_DIR)" % BUILD_DIR)
    lib = pathlib.Path(curvflow.library_path()).resolve()
    assert lib.parent == BUILD_DIR, "library %s is not from the CLI's build %s" % (lib, BUILD_DIR)
    return str(exe)


@pytest.fixture(scope="session")
def shared():
    d = shared_meshes()
    if d is None:
        pytest.skip("SKIP: shared meshes not found (../shared/meshes or $CURVFLOW_SHARED_DIR)")
    return d


def run_cli(cli, *args, check=True):
    """Runs the CLI; returns the CompletedProcess (asserting exit 0 if check)."""
    proc = subprocess.run([cli] + [str(a) for a in args], capture_output=True, text=True)
    if check:
        assert proc.returncode == 0, "curvflow %s: exit %d: %s" % (" ".join(map(str, args)), proc.returncode,
                                                                 proc.stderr)
    return proc


@pytest.fixture(scope="session")
def meshes(cli, tmp_path_factory):
    """Generated test meshes (written by the CLI): name -> path."""
    d = tmp_path_factory.mktemp("meshes")
    out = {}
    for name, args in {
        "icosphere": ["icosphere", "--subdivisions", "2"],
        "bumpy": ["bumpy-sphere", "--subdivisions", "3", "--amplitude", "0.3"],
        "torus": ["torus", "--n-major", "24", "--n-minor", "12"],
        "grid": ["grid", "--nx", "8", "--ny", "8"],
        "cylinder": ["cylinder", "--n-around", "16", "--n-along", "8"],
        "bar": ["bar", "--nx", "10", "--ny", "2", "--nz", "2"],
        # thin limbs that the conformal map crowds (mean Q 2.36 after 10 default steps)
        "limbs": ["limb-sphere", "--subdivisions", "3", "--length", "1.8", "--width", "0.18"],
    }.items():
        path = d / (name + ".obj")
        run_cli(cli, "generate", *args, "-o", path)
        out[name] = path
    return out


def read_jsonl(path):
    with open(path, encoding="utf-8") as fp:
        return [json.loads(line) for line in fp if line.strip()]
