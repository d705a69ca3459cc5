"""The Python examples (examples/python) run at a reduced size and write their figures."""

import os
import pathlib
import struct
import subprocess
import sys
import time

import pytest

from conftest import ROOT

EXAMPLES = sorted((ROOT / "examples" / "python").glob("*.py"))


def png_size(path):
    data = pathlib.Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    width, height = struct.unpack(">II", data[16:24])
    return width, height


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_writes_its_figure(script, tmp_path):
    env = dict(os.environ, TROCHOMILL_EXAMPLE_QUICK="1", MPLBACKEND="Agg")
    t0 = time.monotonic()
    p = subprocess.run([sys.executable, str(script), str(tmp_path)], capture_output=True,
                       text=True, env=env, timeout=120)
    elapsed = time.monotonic() - t0
    assert p.returncode == 0, p.stderr
    out = tmp_path / f"{script.stem}.png"
    assert p.stdout.strip() == str(out)
    width, height = png_size(out)
    assert width >= 600 and height >= 300
    assert elapsed < 30, elapsed  # the bound for the full size; reduced here


def test_every_example_is_tested():
    assert len(EXAMPLES) == 4
