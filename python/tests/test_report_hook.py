"""The report hook (curvflow.report, batch --report) calls `curvflow report`
with a log written by curvflow.write_log; skipped when the tool in use has
no report command or was built without its viewer."""
import re

import pytest

import curvflow


def test_report_from_python(cli, meshes, tmp_path):
    V, F, extras = curvflow.load(meshes["bumpy"])
    V2, log = curvflow.flow(V, F, "spin-willmore", steps=3)
    out, lg = tmp_path / "out.ply", tmp_path / "log.jsonl"
    curvflow.save(out, V2, F, uv=extras["uv"], uv_faces=extras["uv_faces"])
    curvflow.write_log(lg, log)
    run = {"method": "spin-willmore", "steps_requested": 3, "steps_done": 3, "parameters": [["steps", "3"]]}
    try:
        html = curvflow.report(meshes["bumpy"], out, log=lg, run=run, title="python hook",
                               out=tmp_path / "r.html")
    except curvflow.UnsupportedError as e:
        pytest.skip("SKIP: %s" % e)
    text = open(html, encoding="utf-8").read()
    assert "python hook" in text and re.search(r"spin-willmore", text)
    assert len(text) > 10000  # one self-contained file
    with pytest.raises(curvflow.UsageError, match="curvflow report failed"):
        curvflow.report(meshes["bumpy"], meshes["torus"], out=tmp_path / "bad.html")  # other connectivity
