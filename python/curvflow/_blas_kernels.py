"""OpenBLAS's kernels for this process, chosen as the command-line tool
chooses them (docs/linalg.md, "OpenBLAS's kernels").

OpenBLAS picks its kernels once, when it is loaded, from the CPU's model; a
model its release does not know gets the generic SSE3 "Prescott" kernels
even on a CPU with AVX-512, and the factorisations run about 1.8x slower.
OpenBLAS reads OPENBLAS_CORETYPE at that moment only, so it must be in the
environment before anything loads OpenBLAS: numpy does, when the package
imports it. The library answers the question (cf_blas_core_advice); asking
it loads OpenBLAS, so a child process asks, once, and the answer goes into
os.environ, where the CLI runs and worker processes started later find it.

The answer is also kept in CURVFLOW_BLAS_ADVICE (a kernel name, or "none"
when OpenBLAS's own choice is right), so that processes started from here
(the batch runner's workers, scripts run by this one) skip the question,
even if something removed OPENBLAS_CORETYPE from their environment.

If OpenBLAS was loaded before the package (numpy imported first), this
process keeps OpenBLAS's choice; the variable is then set to that choice so
that the CLI runs started from here use the same kernels and results stay
equal bit for bit, and a warning says how to get the faster kernels.
"""
import logging
import os
import subprocess
import sys

_VARIABLE = "OPENBLAS_CORETYPE"
_ANSWER = "CURVFLOW_BLAS_ADVICE"
_PROBE = ("import ctypes, sys\n"
          "lib = ctypes.CDLL(sys.argv[1])\n"
          "lib.cf_blas_core_advice.restype = ctypes.c_char_p\n"
          "advice = lib.cf_blas_core_advice()\n"
          "sys.stdout.write(advice.decode() if advice else '')\n")


def _openblas_loaded():
    try:
        with open("/proc/self/maps") as maps:
            return "libopenblas" in maps.read()
    except OSError:
        return False


def choose_before_loading(library_path):
    """Sets OPENBLAS_CORETYPE when OpenBLAS would take this CPU for an old
    one; to be called before numpy or the library is loaded. Does nothing
    when the variable is set, OpenBLAS is loaded already, or the question
    cannot be asked (no library, no interpreter to run it in)."""
    if os.environ.get(_VARIABLE) or not sys.platform.startswith("linux"):
        return
    if _openblas_loaded():
        return
    known = os.environ.get(_ANSWER)
    if known:
        if known != "none":
            os.environ[_VARIABLE] = known
        return
    if library_path is None or not sys.executable:
        return
    try:
        answer = subprocess.run([sys.executable, "-c", _PROBE, str(library_path)], capture_output=True,
                                text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return
    if answer.returncode != 0:
        return
    core = answer.stdout.strip()
    os.environ[_ANSWER] = core or "none"
    if core:
        os.environ[_VARIABLE] = core


def settle_after_loading(lib):
    """After the library is loaded: if OpenBLAS still runs the fallback
    kernels (it was loaded before the package could choose), keep the CLI
    runs started from this process on the same kernels and say so once."""
    advice = lib.cf_blas_core_advice()
    if not advice:
        return
    running = lib.cf_blas_core()
    os.environ[_VARIABLE] = running.decode()
    logging.getLogger("curvflow").warning(
        "OpenBLAS was loaded before curvflow (numpy imported first?) and runs its generic %s kernels on "
        "this CPU; factorisations would be about 1.8x faster with %s=%s in the environment before Python "
        "starts (or with curvflow imported before numpy). CLI runs started from here use %s too, so that "
        "their results equal this process's.", running.decode(), _VARIABLE, advice.decode(), running.decode())
