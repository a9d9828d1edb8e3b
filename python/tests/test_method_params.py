"""curvflow.method_params includes the step policy common to every method,
with the names, defaults and accepted ranges that `curvflow flow --method
NAME --list-params` prints; every listed parameter is set by name, and out of
its range it is refused with the CLI's message."""
import re

import numpy as np
import pytest

import curvflow
from conftest import run_cli

COMMON = {  # name: (type, default text, accepted values as printed)
    "energy_check": ("bool", "true", "true|false"),
    "backtrack": ("bool", "true", "true|false"),
    "max_halvings": ("int", "10", "[0, 60]"),
    "halving_search": ("bool", "true", "true|false"),
    "step_growth": ("double", "2", "[1, 16]"),
    "rise_tolerance": ("double", "1e-09", "[0, 1]"),
    "divergence_tolerance": ("double", "0.0001", "[0, 1]"),
    "energy_floor": ("double", "1e-12", "[0, 1000000]"),
    "blowup_factor": ("double", None, "[0, 1000000000000]"),
    "divergence_factor": ("double", None, "[0, 1000000000000]"),
}
# the defaults that depend on the method (its step policy descriptor):
# (blowup_factor, divergence_factor); stretch-bend-edit opts out of both
PER_METHOD = {"spin-willmore": ("10", "1"), "explicit-mcf": ("10", "0"), "explicit-bilaplacian": ("10", "0")}
OTHERS = ("0", "0")  # implicit flows: off unless set; stretch-bend-edit: no checks


def _cli_params(cli, method):
    """{name: (default, accepts)} from --list-params, method and common sections."""
    text = run_cli(cli, "flow", "--method", method, "--list-params").stdout
    out = {}
    for line in text.splitlines():
        m = re.match(r"^  (\S+)\s+\[([^\]]*)\] (?:in )?(.*)$", line)
        if m:
            out[m.group(1)] = (m.group(2), m.group(3).strip())
    return out


@pytest.mark.parametrize("method", sorted(curvflow.methods()))
def test_common_params_match_cli(cli, method):
    params = curvflow.method_params(method)
    listed = _cli_params(cli, method)
    checks = dict(zip(("blowup_factor", "divergence_factor"), PER_METHOD.get(method, OTHERS)))
    for name, (kind, default, accepts) in COMMON.items():
        default = checks.get(name, default)
        p = params[name]
        assert p["group"] == "step-policy"
        assert (p["type"], p["default"], p["accepts"]) == (kind, default, accepts)
        assert listed[name] == (default, accepts)
    # every parameter the CLI lists is in method_params with the same default and range, and nothing else
    assert set(params) == set(listed)
    for name, p in params.items():
        assert listed[name][0] == p["default"], name
        if p["type"] in ("double", "int", "bool", "choice"):
            assert listed[name][1] == p["accepts"], name
    assert [n for n, p in params.items() if p["group"] == "step-policy"] == list(COMMON)
    assert params["max_halvings"]["range"] == (0, 60)
    assert params["step_growth"]["range"] == (1.0, 16.0)


def test_common_params_are_set_and_checked():
    curvflow.check_params("implicit-mcf", max_halvings=3, step_growth=1.5, backtrack=False, energy_floor=1e-9)
    with pytest.raises(curvflow.UsageError, match=r"parameter 'max_halvings': 61 is outside \[0, 60\]"):
        curvflow.check_params("implicit-mcf", max_halvings=61)
    with pytest.raises(curvflow.UsageError, match=r"parameter 'step_growth': 0.5 is outside \[1, 16\]"):
        curvflow.check_params("spin-willmore", step_growth=0.5)


def test_common_params_reach_the_flow(meshes):
    """On this bumpy sphere the first implicit-bilaplacian step at time_step
    1 lowers the energy only after 9 halvings: max_halvings=3 stops the run
    there as converged (no step), backtrack=False makes it fail."""
    V, F, _ = curvflow.load(meshes["bumpy"])
    _, log = curvflow.flow(V, F, "implicit-bilaplacian", steps=1, time_step=1.0)
    assert log[1]["residuals"]["time_step_halvings"] == 9
    _, log = curvflow.flow(V, F, "implicit-bilaplacian", steps=1, time_step=1.0, max_halvings=3)
    assert len(log) == 1
    with pytest.raises(curvflow.NumericalError, match="energy rose"):
        curvflow.flow(V, F, "implicit-bilaplacian", steps=1, time_step=1.0, backtrack=False)


def test_blowup_and_divergence_reach_the_flow(meshes):
    """The common blowup_factor / divergence_factor by name: explicit-mcf
    without the rise check at time_step 20 on this bumpy sphere blows up in
    step 2 (area 5.04 -> 2.6e5) under its default factor 10, and runs on
    with blowup_factor=0; spin-willmore keeps the spelling of its former
    options (divergence_factor=0 is accepted, 1.5 too, 0.5 refused by the
    flow's creation)."""
    V, F, _ = curvflow.load(meshes["bumpy"])
    with pytest.raises(curvflow.NumericalError,
                       match=r"iteration 2: explicit-mcf: energy grew from 5.03918 to .*blew up"):
        curvflow.flow(V, F, "explicit-mcf", steps=2, time_step=20.0, energy_check=False)
    _, log = curvflow.flow(V, F, "explicit-mcf", steps=2, time_step=20.0, energy_check=False, blowup_factor=0)
    assert len(log) == 3 and log[2]["energy"] > 10 * log[1]["energy"]
    curvflow.check_params("spin-willmore", divergence_factor=0, blowup_factor=5)
    curvflow.check_params("spin-willmore", divergence_factor=1.5)
    with pytest.raises(curvflow.UsageError,
                       match=r"parameter 'divergence_factor': must be 0 \(off\) or >= 1, got 0.5"):
        curvflow.flow(V, F, "spin-willmore", steps=1, divergence_factor=0.5)
