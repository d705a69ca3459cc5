"""Bergmann 2021: the cutting forces F_x, F_y, F_z over one trochoid cycle of the Inconel 718
slot, a new insert against a worn one (the job's [topography] wear states: a honed edge and a
0.15 mm flank wear land). Writes bergmann_forces_wear.png.

    PYTHONPATH=build/python python3 examples/python/bergmann_forces_wear.py [OUTPUT_DIR]
"""

import os
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import trochomill as tm  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
QUICK = os.environ.get("TROCHOMILL_EXAMPLE_QUICK") == "1"  # the test suite's reduced size


def main(out_dir):
    fig, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for state, (label, style) in enumerate([("new insert", "-"), ("worn insert (VB 0.15 mm)", "--")]):
        job = tm.Job.from_toml(HERE.parent / "bergmann2021" / "trochoidal.toml",
                               set={"topography.state": state})
        if QUICK:
            job.set("slot.length", 6.0)
        cycle = (1, 2) if QUICK else (3, 4)
        f = tm.forces(job, fast=True, cycles=cycle)
        s = f["series"]
        t = s["t_s"] - s["t_s"][0]
        for ax, key, name in zip(axes, ["f_x_n", "f_y_n", "f_z_n"], ["F_x", "F_y", "F_z"]):
            ax.plot(t, s[key], style, lw=0.6, label=f"{label}: max |{name}| "
                    f"{f[key.replace('_n', '_max_n')]:.0f} N")
            ax.set_ylabel(f"{name} (N)")
            ax.legend(fontsize=8, loc="upper right")
    axes[-1].set_xlabel("time in the cycle (s)")
    axes[0].set_title("Forces on the workpiece over one trochoid cycle (Bergmann 2021)")
    fig.tight_layout()
    out = pathlib.Path(out_dir) / "bergmann_forces_wear.png"
    fig.savefig(out, dpi=120)
    print(out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
