"""`trochomill sweep` on one process and on two MPI ranks (docs/PERFORMANCE.md, "Sweeps").

  /usr/bin/python3 bench/sweep_bench.py build/bin/trochomill [points]

1. 64 analyze points of the Wagih elliptical example (a Sobol sample of aspect ratio and
   step), one point at a time on one process, then under `mpirun -np 2`: the scaling
   efficiency T1 / (2 T2), each time less mpirun's own start-up (`mpirun -np 2 trochomill
   --version`), and the files compared byte for byte.
2. The MPI layer's cost per point: 400 points of a cheap evaluation (the mechanism of the
   Pivkin example, a few ms each) on two ranks against one process, per point.
"""

import os
import pathlib
import subprocess
import sys
import tempfile
import time

CLI = sys.argv[1] if len(sys.argv) > 1 else "build/bin/trochomill"
POINTS = int(sys.argv[2]) if len(sys.argv) > 2 else 64
ROOT = pathlib.Path(__file__).resolve().parents[1]
ENV = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
def mpirun(ranks):
    return ["mpirun", "-np", str(ranks), "--oversubscribe", "--mca", "btl", "self,vader",
            "--mca", "oob_tcp_if_include", "lo"]


def timed(cmd):
    t = time.perf_counter()
    subprocess.run(cmd, check=True, env=ENV, stdout=subprocess.DEVNULL)
    return time.perf_counter() - t


def main():
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="trochomill-sweep-bench-"))

    cases = [
        ("analyze", [str(ROOT / "examples/wagih2023/elliptical.toml"), "--range",
                     "path.aspect_ratio=0.5:1.2", "--range", "path.step=0.5:1.5", "--samples",
                     str(POINTS)], POINTS),
        ("mechanism", [str(ROOT / "examples/pivkin2025/trochoidal.toml"), "--eval", "mechanism",
                       "--range", "path.step=0.05:0.2", "--range",
                       "cutting.feed_per_tooth=0.02:0.08", "--samples", "400"], 400),
    ]
    for name, args, n in cases:
        plain, one, two = (tmp / f"{name}-{k}.csv" for k in ("plain", "1", "2"))
        t0 = timed([CLI, "sweep", *args, "--threads", "1", "-o", str(plain)])
        t1 = timed([*mpirun(1), CLI, "sweep", *args, "--threads", "1", "-o", str(one)])
        t2 = timed([*mpirun(2), CLI, "sweep", *args, "--threads", "1", "-o", str(two)])
        same = plain.read_bytes() == one.read_bytes() == two.read_bytes()
        print(f"{name}: {n} points; one process without mpirun {t0:.2f} s ({1e3 * t0 / n:.1f} ms "
              f"a point); mpirun -np 1 {t1:.2f} s, -np 2 {t2:.2f} s: efficiency T1 / (2 T2) "
              f"{t1 / (2 * t2):.2f}; the MPI layer's cost (2 T2 - T1) / points "
              f"{1e3 * (2 * t2 - t1) / n:.2f} ms a point; files identical: {same}")


if __name__ == "__main__":
    main()
