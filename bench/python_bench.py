"""The Python module's costs, side by side in one run (docs/PERFORMANCE.md):

1. analyze on the Wagih elliptical example through Python (the C++ call, the JSON document
   as a dict and the series as numpy arrays) against the C++ call alone
   (analyze_with_forces, timed inside the module);
2. monitor on 10 s of 100 kHz float64 numpy data (both bands filtered forward and backward,
   RMS windows, cycles, flags) against scipy.signal.sosfilt of the same two filters (one
   forward pass each).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py [REPEAT]
"""

import pathlib
import sys
import time

import numpy as np
import scipy.signal
import trochomill as tm

ROOT = pathlib.Path(__file__).resolve().parents[1]


def best(f, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main(repeat):
    job = tm.Job.from_toml(ROOT / "examples" / "wagih2023" / "elliptical.toml")
    path = tm.plan(job)
    tm.analyze(path)  # warm up (page faults, the json module)
    # Interleaved rounds: the machine's load drifts alike for both.
    py_t, cpp_t = [], []
    for _ in range(repeat):
        py_t.append(best(lambda: tm.analyze(path), 1))
        cpp_t.append(tm._trochomill._analyze_seconds(path, 1))
    py_s, cpp_s = min(py_t), min(cpp_t)
    print(f"analyze (Wagih elliptical, {path.duration_s:.1f} s of program): Python {py_s * 1e3:.1f} ms, "
          f"C++ {cpp_s * 1e3:.1f} ms, Python / C++ {py_s / cpp_s:.3f}")

    rate = 100000.0
    rng = np.random.default_rng(1)
    x = rng.standard_normal(int(10 * rate))
    low, high = tm._trochomill._monitor_filters(rate)
    for ours, theirs, name in [(low, scipy.signal.butter(4, [2000, 5000], "bandpass", fs=rate, output="sos"), "low"),
                               (high, scipy.signal.butter(4, [8000, 13000], "bandpass", fs=rate, output="sos"), "high")]:
        # The same filters: equal responses (the sections may pair poles and split gain
        # differently).
        w, h_ours = scipy.signal.sosfreqz(ours, worN=4096, fs=rate)
        _, h_theirs = scipy.signal.sosfreqz(theirs, worN=4096, fs=rate)
        assert np.allclose(h_ours, h_theirs, rtol=0, atol=1e-9), name
    mon_s = best(lambda: tm.monitor(x, rate), repeat)
    sci_s = best(lambda: (scipy.signal.sosfilt(low, x), scipy.signal.sosfilt(high, x)), repeat)
    print(f"monitor (10 s at 100 kHz, float64): trochomill {mon_s * 1e3:.1f} ms, "
          f"scipy sosfilt of the two filters {sci_s * 1e3:.1f} ms, scipy / trochomill {sci_s / mon_s:.2f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 7)
