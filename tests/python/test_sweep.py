"""`trochomill sweep` as a user runs it: its Sobol points against scipy's, and a run killed
with SIGKILL half-way then resumed, against an uninterrupted run."""

import csv
import json
import pathlib
import io
import os
import shutil
import signal
import subprocess
import time

import numpy as np
import pytest
from scipy.stats import qmc

from conftest import CLI, run_cli


def table(path):
    rows = list(csv.reader(io.StringIO(path.read_text())))
    return rows[0], rows[1:]


def test_sobol_points_are_scipys(wagih, tmp_path):
    out = tmp_path / "s.csv"
    run_cli("sweep", wagih, "--range", "path.step=0.5:1.5", "--range", "path.aspect_ratio=0.6:1.2",
            "--samples", "8", "-o", out)
    head, rows = table(out)
    got = np.array([[float(r[head.index("path.step")]), float(r[head.index("path.aspect_ratio")])]
                    for r in rows])
    # scipy's unscrambled Sobol sequence starts at the origin, which trochomill (Boost's
    # generator) skips; the values are printed to 12 significant digits.
    u = qmc.Sobol(d=2, scramble=False).random(9)[1:]
    want = np.array([0.5, 0.6]) + u * np.array([1.0, 0.6])
    np.testing.assert_allclose(got, want, rtol=1e-11)


def test_killed_run_resumes_to_the_same_file(pivkin, tmp_path):
    args = ["sweep", str(pivkin), "--eval", "mechanism", "--range", "path.step=0.05:0.2",
            "--range", "cutting.feed_per_tooth=0.02:0.08", "--samples", "48", "--threads", "1"]
    whole = tmp_path / "whole.csv"
    run_cli(*args, "-o", whole)
    killed = tmp_path / "killed.csv"
    p = subprocess.Popen([CLI, *args, "-o", str(killed)], stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    # Kill it once a few rows are in (or give up waiting after 60 s and kill it anyway).
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and p.poll() is None:
        if killed.exists() and killed.read_text().count("\n") >= 6:
            break
        time.sleep(0.01)
    if p.poll() is None:
        os.kill(p.pid, signal.SIGKILL)
    p.wait()
    rows_before = killed.read_text().count("\n") - 1
    assert rows_before < 48, "the run ended before it was killed: nothing was resumed"
    r = run_cli(*args, "-o", killed, "--resume")
    assert killed.read_text() == whole.read_text()
    assert f"({48 - rows_before} run now" in r.stdout, r.stdout


def test_bad_sweeps_exit_2(wagih, tmp_path):
    out = tmp_path / "bad.csv"
    for extra, message in [
        (["--vary", "path.nope=1,2"], "--vary path.nope: no such job key"),
        (["--range", "path.step=2:1"], "finite numbers lo < hi"),
        (["--range", "path.step=1:2"], "--range needs --samples"),
        (["--vary", "path.step=1,2", "--eval", "optimize"], "--eval 'optimize': analyze, mechanism"),
        (["--vary", "path.step=1,2", "--cycles", "1:2"], "--cycles is for --eval forces or simulate"),
    ]:
        p = run_cli("sweep", wagih, *extra, "-o", out, check=False)
        assert p.returncode == 2, (extra, p.stderr)
        assert message in p.stderr, (extra, p.stderr)
        assert not out.exists()


def test_optimize_writes_a_job_that_holds_its_constraint(tmp_path):
    """The best job written by optimize, analysed again by the CLI, keeps h_max under the
    limit, and its feed is the closed-form optimum F = h_max Z n (a straight full slot cuts a
    chip f_z = F / (Z n)) within 0.5 %; a choice variable runs each of its values."""
    job = tmp_path / "linear.toml"
    src = (pathlib.Path(__file__).resolve().parents[2] / "examples/wagih2023/trochoidal.toml")
    job.write_text(src.read_text().replace('type = "trochoidal"', 'type = "linear"'))
    best = tmp_path / "best.toml"
    r = run_cli("optimize", job, "--var", "cutting.feed_rate=100:2000",
                "--var", 'path.direction="climb","conventional"', "--maximize",
                "mrr_total_mm3_per_min", "--subject-to", "h_max_mm<=0.05", "--max-evals", "60",
                "-o", best, "--json", "-")
    result = json.loads(r.stdout)
    assert result["evaluations"] <= 120
    again = json.loads(run_cli("analyze", best, "--json", "-").stdout)
    assert again["h_max_mm"] <= 0.05 * (1 + 1e-9)
    feed = float(result["best"]["values"]["cutting.feed_rate"])
    assert abs(feed - 0.05 * 4 * 2000) <= 0.005 * 400, feed
    assert result["best"]["margins"]["h_max_mm<=0.05"] >= -1e-9 * 0.05


def test_bad_optimizations_exit_2(wagih, tmp_path):
    out = tmp_path / "best.toml"
    for extra, message in [
        (["--var", "path.step=0.5:1.5", "--maximize", "mrr"], "--maximize mrr: not a metric of --eval analyze"),
        (["--var", "path.step=0.5:1.5", "--maximize", "h_max_mm", "--subject-to", "h_max_mm<0.1"],
         "expected METRIC<=VALUE or METRIC>=VALUE"),
        (["--var", "path.type=1:2", "--maximize", "h_max_mm"], "not a number"),
        (["--var", "path.step=0.5:1.5"], "give --maximize or --minimize"),
    ]:
        p = run_cli("optimize", wagih, *extra, "-o", out, check=False)
        assert p.returncode == 2, (extra, p.stderr)
        assert message in p.stderr, (extra, p.stderr)
        assert not out.exists()


MPIRUN = shutil.which("mpirun")
# As root (CI) Open MPI wants both confirmations; shared memory between the two ranks and the
# runtime's own connections on loopback only.
MPI_ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
MPI_ARGS = ["-np", "2", "--oversubscribe", "--mca", "btl", "self,vader", "--mca",
            "oob_tcp_if_include", "lo"]


@pytest.mark.skipif(MPIRUN is None or os.environ.get("TROCHOMILL_MPI") != "ON",
                    reason="no mpirun, or a build without MPI")
def test_two_ranks_write_the_single_process_file_and_resume_it(pivkin, tmp_path):
    args = ["sweep", str(pivkin), "--eval", "mechanism", "--range", "path.step=0.05:0.2",
            "--range", "cutting.feed_per_tooth=0.02:0.08", "--samples", "40"]
    single = tmp_path / "single.csv"
    run_cli(*args, "--threads", "1", "-o", single)
    mpi = tmp_path / "mpi.csv"
    p = subprocess.run([MPIRUN, *MPI_ARGS, CLI, *args, "-o", str(mpi)], capture_output=True,
                       text=True, env=MPI_ENV, timeout=300)
    assert p.returncode == 0, p.stderr
    assert mpi.read_text() == single.read_text()
    # Stopped after 11 rows and in the middle of the next (a node lost mid-write), then
    # resumed on two ranks: the same file again.
    text = single.read_text()
    cut = [i for i, c in enumerate(text) if c == "\n"][11] + 20
    resumed = tmp_path / "resumed.csv"
    resumed.write_text(text[:cut])
    p = subprocess.run([MPIRUN, *MPI_ARGS, CLI, *args, "-o", str(resumed), "--resume"],
                       capture_output=True, text=True, env=MPI_ENV, timeout=300)
    assert p.returncode == 0, p.stderr
    assert resumed.read_text() == single.read_text()
    assert "(29 run now" in p.stdout, p.stdout
    # A bad start on rank 0 (the file exists) ends every rank: exit 2, the message, no hang.
    p = subprocess.run([MPIRUN, *MPI_ARGS, CLI, *args, "-o", str(mpi)], capture_output=True,
                       text=True, env=MPI_ENV, timeout=120)
    assert p.returncode == 2
    assert "exists: --resume continues that sweep" in p.stderr
