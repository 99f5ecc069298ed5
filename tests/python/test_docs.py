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
    blocks = cells()
    assert len(blocks) >= 6
    ns = {}
    ran = 0
    for code in blocks:
        if "matplotlib" in code and importlib.util.find_spec("matplotlib") is None:
            continue  # the plotting cell needs matplotlib, not part of dfle
        if "DFLE_DATA_DIR" in code and not os.environ.get("DFLE_DATA_DIR"):
            continue
        exec(compile(code, DOC, "exec"), ns)
        ran += 1
    assert ran >= 4
    assert ns["run"].converged and ns["ens"].ok == 8
    assert ns["df"].shape[0] == 8
    assert ns["law"].compiled()["rate"] is True

