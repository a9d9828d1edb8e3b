"""OpenBLAS's kernels as the package chooses them (curvflow/_blas_kernels.py;
docs/linalg.md, "OpenBLAS's kernels"): a process that imports curvflow
runs the same kernels as the CLI, never the generic Prescott ones on a CPU
with AVX2; when numpy loaded OpenBLAS first, the process keeps OpenBLAS's
choice, says so, and the CLI runs it starts use that choice too (so that
their results stay equal bit for bit); a user's OPENBLAS_CORETYPE stands.
The answer is kept in CURVFLOW_BLAS_ADVICE for the processes started from
there. Each case runs in a fresh interpreter: the choice is made once, at
load."""
import json
import os
import subprocess
import sys

from conftest import ROOT

_REPORT = ("import json, os, subprocess, sys\n"
           "%s\n"
           "import curvflow\n"
           "from curvflow import _lib\n"
           "running = _lib.lib().cf_blas_core()\n"
           "child = subprocess.run([sys.argv[1], '--version'], capture_output=True, text=True).stdout\n"
           "print(json.dumps({'running': running.decode() if running else None,\n"
           "                  'variable': os.environ.get('OPENBLAS_CORETYPE'), 'cli': child,\n"
           "                  'answer': os.environ.get('CURVFLOW_BLAS_ADVICE')}))\n")


def _cpu_has_avx2():
    try:
        with open("/proc/cpuinfo") as f:
            return any(line.startswith("flags") and " avx2" in line for line in f)
    except OSError:
        return False


def _fresh_process(cli, first_import="", coretype=None, answer=None):
    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_CORETYPE", "CURVFLOW_BLAS_ADVICE")}
    if answer is not None:
        env["CURVFLOW_BLAS_ADVICE"] = answer
    if coretype is not None:
        env["OPENBLAS_CORETYPE"] = coretype
    env["PYTHONPATH"] = str(ROOT / "python")
    proc = subprocess.run([sys.executable, "-c", _REPORT % first_import, cli], capture_output=True, text=True,
                          env=env)
    assert proc.returncode == 0, proc.stderr
    report = json.loads(proc.stdout)
    line = next((l for l in report["cli"].splitlines() if l.startswith("OpenBLAS kernels: ")), "")
    report["cli"] = line.split()[2] if line else None
    return report, proc.stderr


def test_package_runs_the_clis_kernels(cli):
    report, stderr = _fresh_process(cli)
    assert report["running"] is not None
    assert report["running"] == report["cli"], report
    if _cpu_has_avx2():
        assert report["running"] != "Prescott", report
    assert "OpenBLAS was loaded before curvflow" not in stderr
    # the answer is kept for the processes started from there: "none" when OpenBLAS chose right
    assert report["answer"] == (report["variable"] or "none"), report
    # a process that inherits the answer but lost OPENBLAS_CORETYPE runs the same kernels
    again, _ = _fresh_process(cli, answer=report["answer"])
    assert again["running"] == report["running"] and again["cli"] == report["cli"], again


def test_numpy_first_keeps_one_choice_for_the_process_and_its_cli_runs(cli):
    report, stderr = _fresh_process(cli, first_import="import numpy")
    # numpy loaded OpenBLAS before the package could choose: whatever OpenBLAS chose stands,
    # and the CLI started from this process runs the same kernels
    assert report["running"] == report["cli"], report
    fell_back = report["running"] == "Prescott" and _cpu_has_avx2()
    assert ("OpenBLAS was loaded before curvflow" in stderr) == fell_back, stderr
    if fell_back:
        assert report["variable"] == "Prescott"


def test_users_choice_stands(cli):
    report, stderr = _fresh_process(cli, coretype="Prescott")
    assert report == {"running": "Prescott", "variable": "Prescott", "cli": "Prescott", "answer": None}, report
    assert "OpenBLAS was loaded before curvflow" not in stderr
