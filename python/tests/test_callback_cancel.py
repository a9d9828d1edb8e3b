"""Progress callback and cancellation through the library's progress hook
(CF_ERR_CANCELLED): a callback that returns True stops the flow, one that
raises cancels it and its exception comes back, Ctrl-C (SIGINT) cancels at
the end of the current step and raises KeyboardInterrupt, and no file is
left half-written."""
import os
import signal
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import curvflow
from conftest import ROOT


@pytest.fixture(scope="module")
def bumpy(meshes):
    V, F, _ = curvflow.load(meshes["bumpy"])
    return V, F


def test_callback_sees_every_step_in_order(bumpy):
    seen = []
    V_out, log = curvflow.flow(*bumpy, "spin-willmore", steps=5, callback=seen.append)
    assert [e["iteration"] for e in seen] == [1, 2, 3, 4, 5]
    assert seen == log[1:]  # the same entries as the log (entry 0 is the start)
    assert log[0]["iteration"] == 0
    assert all(b["energy"] < a["energy"] for a, b in zip(log, log[1:]))  # Willmore descent
    assert set(seen[0]["residuals"]) >= {"constraint"}
    assert seen[0]["seconds"]["total"] > 0


def test_callback_returning_true_stops_normally(bumpy):
    def stop_at_3(entry):
        return entry["iteration"] == 3
    V3, log = curvflow.flow(*bumpy, "spin-willmore", steps=10, callback=stop_at_3)
    assert [e["iteration"] for e in log] == [0, 1, 2, 3]
    ref, _ = curvflow.flow(*bumpy, "spin-willmore", steps=3)
    assert np.array_equal(V3, ref)  # the state after step 3 is kept


def test_callback_exception_cancels_and_is_reraised(bumpy):
    class Stop(Exception):
        pass

    def boom(entry):
        if entry["iteration"] == 2:
            raise Stop("enough")
    with pytest.raises(Stop, match="enough") as e:
        curvflow.flow(*bumpy, "implicit-mcf", steps=50, callback=boom)
    assert e.value.log[-1]["iteration"] == 2  # no step after the one that raised
    ref, _ = curvflow.flow(*bumpy, "implicit-mcf", steps=2)
    assert np.array_equal(e.value.last_positions, ref)


def test_keyboard_interrupt_in_callback(bumpy):
    """A KeyboardInterrupt raised inside the callback (as a custom SIGINT
    handler would) cancels the flow and is raised with the state reached."""
    def interrupt(entry):
        if entry["iteration"] == 4:
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt, match="cancelled after iteration 4") as e:
        curvflow.flow(*bumpy, "spin-willmore", steps=20, callback=interrupt)
    assert e.value.last_positions.shape == bumpy[0].shape and len(e.value.log) == 5
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_sigint_handler_restored(bumpy):
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    curvflow.flow(*bumpy, "implicit-mcf", steps=1)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_bad_callback(bumpy):
    with pytest.raises(TypeError, match="callback"):
        curvflow.flow(*bumpy, "implicit-mcf", callback=3)


LONG_FLOW = textwrap.dedent("""
    import os, sys
    sys.path.insert(0, {python!r})
    import curvflow
    V, F, _ = curvflow.load({mesh!r})
    def progress(entry):
        if entry["iteration"] == 3:
            print("running", flush=True)
    try:
        V2, log = curvflow.flow(V, F, "implicit-mcf", steps=10**8, time_step=1e-9, callback=progress)
    except KeyboardInterrupt as e:
        print("interrupted at", e.log[-1]["iteration"], e.last_positions.shape, flush=True)
        raise
    curvflow.save({out!r}, V2, F)
""")


def test_sigint_cancels_a_long_flow(meshes, tmp_path):
    """Ctrl-C in a script running a long flow: the flow stops through the
    library's cancel hook, KeyboardInterrupt reaches the script (which can
    still see the state reached), the process ends as interrupted, and the
    output it would have written does not exist (nor any temporary file)."""
    out = tmp_path / "never.ply"
    script = LONG_FLOW.format(python=str(ROOT / "python"), mesh=str(meshes["bumpy"]), out=str(out))
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=tmp_path)
    try:
        assert proc.stdout.readline().strip() == "running"
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert stdout.startswith("interrupted at "), stderr
    assert "(%d, 3)" % len(curvflow.load(meshes["bumpy"])[0]) in stdout
    assert proc.returncode in (-signal.SIGINT, 130, 1)
    assert "KeyboardInterrupt: curvflow: flow cancelled after iteration" in stderr
    assert os.listdir(tmp_path) == []  # no result and no temporary file


def test_sigint_during_save_leaves_old_file_intact(meshes, tmp_path):
    """Saving is atomic (the library's temp + rename): however a process
    running save in a loop is interrupted, the target is always a complete
    file, the old one or the new one."""
    V, F, _ = curvflow.load(meshes["bumpy"])
    big = tmp_path / "big.obj"
    k = 40  # a larger mesh (40 copies side by side) so that a save takes a while
    Vb = np.concatenate([V + [3.0 * i, 0, 0] for i in range(k)])
    Fb = np.concatenate([F + len(V) * i for i in range(k)])
    curvflow.save(big, Vb, Fb)
    target = tmp_path / "target.ply"
    script = textwrap.dedent("""
        import sys
        sys.path.insert(0, {python!r})
        import curvflow
        V, F, _ = curvflow.load({big!r})
        print("loaded", flush=True)
        while True:
            curvflow.save({target!r}, V, F, ply_encoding="ascii")
    """).format(python=str(ROOT / "python"), big=str(big), target=str(target))
    for delay in (0.05, 0.2, 0.5):
        proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
        assert proc.stdout.readline().strip() == "loaded"
        try:
            proc.wait(timeout=delay)
        except subprocess.TimeoutExpired:
            pass
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
        if target.exists():
            V2, F2, _ = curvflow.load(target)
            assert np.array_equal(V2, Vb) and np.array_equal(F2, Fb)
    assert sorted(p.name for p in tmp_path.iterdir()) in (["big.obj"], ["big.obj", "target.ply"])
