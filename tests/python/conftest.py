"""Shared fixtures of the Python module's tests: the CLI they compare with, the examples, and
a reader of the CLI's CSV that keeps each cell's printed text (its last digit sets how close
the module's value must be)."""

import csv
import io
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"
CLI = os.environ.get("TROCHOMILL_CLI", str(ROOT / "build" / "bin" / "trochomill"))


def run_cli(*args, check=True):
    """Runs the CLI; returns its stdout (text)."""
    p = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, timeout=300)
    if check and p.returncode != 0:
        raise AssertionError(f"trochomill {' '.join(map(str, args))}: {p.returncode}\n{p.stderr}")
    return p


def cli_json(*args):
    return json.loads(run_cli(*args, "--json", "-").stdout)


def cli_csv(*args, option="--csv"):
    """The CLI's CSV as {column: [cell text]}."""
    text = run_cli(*args, option, "-").stdout
    rows = list(csv.reader(io.StringIO(text)))
    return {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])}


def half_last_digit(cell):
    """Half a unit of the last printed digit of a CSV cell: how far the printed value may be
    from the value it was printed from."""
    mantissa, _, exponent = cell.lower().partition("e")
    decimals = len(mantissa.partition(".")[2])
    return 0.5 * 10.0 ** (int(exponent or 0) - decimals)


def assert_printed(values, cells, what):
    """Every value equals its CSV cell to the cell's last printed digit (the half-unit of
    that digit, and 1e-12 relative for the decimal conversion itself)."""
    values = np.asarray(values, dtype=float)
    assert len(values) == len(cells), f"{what}: {len(values)} values, {len(cells)} rows"
    printed = np.array([float(c) for c in cells])
    tol = np.array([half_last_digit(c) for c in cells]) + 1e-12 * np.abs(printed)
    bad = np.flatnonzero(np.abs(values - printed) > tol)
    assert bad.size == 0, f"{what}: row {bad[0]}: {values[bad[0]]!r} printed {cells[bad[0]]}"


@pytest.fixture(scope="session")
def wagih():
    return EXAMPLES / "wagih2023" / "elliptical.toml"


@pytest.fixture(scope="session")
def pivkin():
    return EXAMPLES / "pivkin2025" / "trochoidal.toml"


@pytest.fixture(scope="session")
def bergmann():
    return EXAMPLES / "bergmann2021" / "trochoidal.toml"
