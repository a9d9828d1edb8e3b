"""Hook for the one-file HTML report (issue 14, item 2).

The report is written by the command-line tool (`curvflow report IN OUT
[--log LOG] -o report.html`), so Python calls that command instead of
carrying a second implementation. When the library gains a C entry point
for the report, only this function changes; callers (curvflow.batch's
--report, scripts) keep the same signature.
"""
import json
import os
import pathlib
import shutil
import subprocess
import tempfile

from .errors import UnsupportedError, UsageError


def cli_path():
    """The curvflow executable: $CURVFLOW_CLI, else the one next to the
    library in use (the build tree holds both), else `curvflow` on PATH.
    None if there is none."""
    env = os.environ.get("CURVFLOW_CLI")
    if env:
        return env
    try:
        from . import _lib
        candidate = pathlib.Path(_lib.lib().curvflow_path).parent / "curvflow"
        if candidate.is_file() and os.access(candidate, os.X_OK):
            return str(candidate)
    except OSError:
        pass
    return shutil.which("curvflow")


def report(input_path, output_path=None, log=None, out="report.html", run=None, title=None, timeout=None):
    """Writes the HTML report of a run: `input_path` is the input mesh (or a
    run directory), `output_path` the result mesh, `log` the JSONL log
    (curvflow.write_log or the CLI's --log), `run` the run description (a
    path, or a dict with the keys of the demo's run.json: method, input,
    output, steps_requested, steps_done, message, parameters as [name, value]
    pairs, seconds {"run": ...}), `title` the page title, `out` the HTML
    file. Returns `out`. Raises UnsupportedError when the curvflow tool in
    use has no `report` command or no viewer, UsageError with the tool's
    message when it fails."""
    exe = cli_path()
    if exe is None:
        raise UnsupportedError("curvflow.report: no curvflow executable found (set CURVFLOW_CLI)")
    probe = subprocess.run([exe, "report", "--help"], capture_output=True, text=True)
    if probe.returncode != 0:
        raise UnsupportedError("curvflow.report: %s has no 'report' command" % exe)
    args = [exe, "report", os.fspath(input_path)]
    if output_path is not None:
        args.append(os.fspath(output_path))
    if log is not None:
        args += ["--log", os.fspath(log)]
    if title is not None:
        args += ["--title", title]
    args += ["-o", os.fspath(out)]
    with tempfile.TemporaryDirectory() as tmp:
        if isinstance(run, dict):
            path = os.path.join(tmp, "run.json")
            with open(path, "w", encoding="utf-8") as fp:
                json.dump(run, fp)
            args += ["--run", path]
        elif run is not None:
            args += ["--run", os.fspath(run)]
        proc = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        msg = proc.stderr.strip()
        cls = UnsupportedError if "report viewer" in msg else UsageError
        raise cls("curvflow report failed (exit %d): %s" % (proc.returncode, msg))
    return os.fspath(out)
