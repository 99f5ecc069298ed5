"""doc/python.md's code runs, cell after cell, as a notebook would."""
import importlib.util
import os
import re

import pytest

DOC = os.path.join(os.path.dirname(__file__), "..", "..", "doc", "python.md")


def cells():
    text = open(DOC).read()
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_tutorial_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")     # no display needed
    blocks = cells()
    assert len(blocks) >= 6
    ns = {}
    skipped = []
    for code in blocks:
        if "matplotlib" in code and importlib.util.find_spec("matplotlib") is None:
            skipped.append("the plotting cell (no matplotlib: install python3-matplotlib)")
            continue
        if "DFLE_DATA_DIR" in code and not os.environ.get("DFLE_DATA_DIR"):
            skipped.append("the DEM cell (no DFLE_DATA_DIR)")
            continue
        exec(compile(code, DOC, "exec"), ns)
    assert ns["run"].converged and ns["ens"].ok == 8
    assert ns["df"].shape[0] == 8
    assert ns["law"].compiled()["rate"] is True
    assert ns["ens2"].workers == 2
    if "dem" in ns:
        assert ns["p"].get("A").size > 10 and 0 < ns["fit"].r2 <= 1
    if "fig" in ns:
        png = tmp_path / "landscape.png"
        assert png.stat().st_size > 10000
        out = os.environ.get("DFLE_TUTORIAL_FIGURES")   # to look at it
        if out:
            import shutil
            shutil.copy(png, out)
    if skipped:
        pytest.skip("every other cell ran; skipped " + "; ".join(skipped))
