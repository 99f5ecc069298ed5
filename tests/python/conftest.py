import os
import subprocess

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BUILD = os.environ.get("BUILD", "build")
DFLE = os.path.join(ROOT, BUILD, "dfle")


def run_lua(tmp_path, source):
    """Run a Lua script through the dfle command; its stdout lines."""
    script = tmp_path / "case.lua"
    script.write_text(source)
    out = subprocess.run([DFLE, "-q", str(script)], capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    return out.stdout.split()


@pytest.fixture
def lua(tmp_path):
    return lambda source: run_lua(tmp_path, source)
