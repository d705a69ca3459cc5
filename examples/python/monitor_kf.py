"""Pivkin 2025's vibroacoustic monitor on a synthetic signal: k_f = RMS(low band) / RMS(high
band) over time and per trochoid cycle, on a recording whose k_f drifts up by 50 % as the
tool wears (the monitor flags it past monitor.wear_ratio, 1.3, times the first cycles' level),
and k_f against the cycle phase, one line per cycle. Writes monitor_kf.png.

    PYTHONPATH=build/python python3 examples/python/monitor_kf.py [OUTPUT_DIR]
"""

import os
import pathlib
import sys
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trochomill as tm  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
QUICK = os.environ.get("TROCHOMILL_EXAMPLE_QUICK") == "1"  # the test suite's reduced size


def main(out_dir):
    job = tm.Job.from_toml(HERE.parent / "pivkin2025" / "trochoidal.toml")
    sig = tm.synth_signal(job, rate_hz=40000 if QUICK else 100000, cycles=4 if QUICK else 12,
                          wear_drift=0.5)
    r = tm.monitor(sig["samples"], sig["rate_hz"], job=job, start_s=sig["start_s"])
    w = r["windows"]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    ax1.plot(w["t_s"], w["k_f"], lw=0.5, color="grey", label="k_f per window")
    starts = [c["start_s"] for c in r["cycle_details"]]
    ends = [c["end_s"] for c in r["cycle_details"]]
    ax1.hlines(r["k_f_per_cycle"], starts, ends, color="tab:red", lw=2, label="k_f per cycle")
    # The wear flag's level: monitor.wear_ratio (the job's, else its default) times the
    # reference, the first cycles' k_f level.
    ratio = next(k["default"] for k in tm.keys() if k["section"] == "monitor" and k["key"] == "wear_ratio")
    ratio = job.to_dict().get("monitor", {}).get("wear_ratio", float(ratio))
    threshold = ratio * r["reference_k_f"]
    ax1.axhline(threshold, color="tab:red", ls="--", lw=0.8, label=f"wear threshold {threshold:.2f}")
    ax1.set_xlabel("time (s)")
    ax1.set_ylabel("k_f = RMS(low) / RMS(high)")
    flags = "; ".join(r["flags"]) if r["flags"] else "none"
    ax1.set_title(textwrap.fill("flags: " + flags, 70), fontsize=8)
    ax1.legend(fontsize=8)
    for c in r["cycle_details"]:
        profile = np.array([np.nan if v is None else v for v in c["k_f_profile"]], dtype=float)
        phase = (np.arange(len(profile)) + 0.5) / len(profile)
        ax2.plot(phase, profile, lw=0.8)
    ax2.set_xlabel("cycle phase")
    ax2.set_ylabel("k_f")
    ax2.set_title("k_f over the cycle, one line per cycle", fontsize=9)
    fig.suptitle("Vibroacoustic monitor (Pivkin 2025) on a synthetic signal")
    fig.tight_layout()
    out = pathlib.Path(out_dir) / "monitor_kf.png"
    fig.savefig(out, dpi=120)
    print(out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
