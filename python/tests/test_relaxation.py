"""spin-willmore's tangential relaxation from the command line and Python
(docs/spin.md, "Tangential relaxation"): on a star with thin limbs the option
lowers the result's mean Q against the input, its log counts the sweeps
kept, and a run without it whose result is above mean Q 1.5 names the
option in a note (not with -q, not with the option, not below 1.5)."""
import curvflow
from conftest import read_jsonl, run_cli


def _mean_q(V0, V1, F):
    return curvflow.compare(V0, V1, F)["quasi_conformal_error"]["mean"]  # area-weighted


def test_relaxation_on_thin_limbs(cli, meshes, tmp_path):
    star = meshes["limbs"]
    V, F, _ = curvflow.load(star)
    plain = run_cli(cli, "flow", star, "-o", tmp_path / "a.obj", "--method", "spin-willmore")
    relaxed = run_cli(cli, "flow", star, "-o", tmp_path / "b.obj", "--method", "spin-willmore", "-p", "relaxation=10",
                      "--log", tmp_path / "b.jsonl")
    q_plain = _mean_q(V, curvflow.load(tmp_path / "a.obj")[0], F)
    q_relaxed = _mean_q(V, curvflow.load(tmp_path / "b.obj")[0], F)
    # measured: 2.363 and 1.693
    assert q_plain > 2.2 and q_relaxed < 1.8
    assert "note: the result's mean Q against the input is %.3f" % q_plain in plain.stderr
    assert "-p relaxation=10" in plain.stderr
    assert "note:" not in relaxed.stderr
    log = read_jsonl(tmp_path / "b.jsonl")
    sweeps = [step["residuals"]["relaxation_sweeps"] for step in log[1:]]
    assert max(sweeps) == 10 and all(s == int(s) and 0 <= s <= 10 for s in sweeps)
    w = [step["terms"]["W/4pi"] for step in log]
    assert all(b <= a for a, b in zip(w, w[1:]))
    quiet = run_cli(cli, "flow", star, "-o", tmp_path / "c.obj", "--method", "spin-willmore", "-q",
                    "--log", tmp_path / "c.jsonl")
    assert quiet.stderr == ""
    assert "relaxation_sweeps" not in read_jsonl(tmp_path / "c.jsonl")[-1]["residuals"]  # only with the option
    # a result under the bound has no note
    calm = run_cli(cli, "flow", meshes["bumpy"], "-o", tmp_path / "d.obj", "--method", "spin-willmore")
    assert "note:" not in calm.stderr
