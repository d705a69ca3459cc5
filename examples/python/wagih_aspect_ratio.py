"""Wagih 2023: the largest chip h_max and the removal rate of an elliptical trochoidal slot
against the aspect ratio r_e = b / a of its ellipses (Wagih 2023, Sections 3-5), from the
exact engagement. Writes wagih_aspect_ratio.png.

    PYTHONPATH=build/python python3 examples/python/wagih_aspect_ratio.py [OUTPUT_DIR]
"""

import os
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trochomill as tm  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
QUICK = os.environ.get("TROCHOMILL_EXAMPLE_QUICK") == "1"  # the test suite's reduced size


def main(out_dir):
    job = tm.Job.from_toml(HERE.parent / "wagih2023" / "elliptical.toml")
    if QUICK:
        job.set("slot.length", 8.0)
    ratios = np.linspace(0.6, 1.6, 5 if QUICK else 11)
    study = tm.compare(job, {"path.aspect_ratio": list(ratios)})
    assert all(study["ok"]), study["error"]
    fig, ax = plt.subplots(figsize=(7, 4.2))
    ax.plot(ratios, 1000 * study["cycle_h_max_mm"], "o-", color="tab:blue", label="h_max (steady cycle)")
    ax.set_xlabel("aspect ratio r_e = b / a")
    ax.set_ylabel("largest chip h_max (um)", color="tab:blue")
    ax2 = ax.twinx()
    ax2.plot(ratios, study["cycle_mrr_mm3_per_min"] / 1000, "s--", color="tab:red",
             label="MRR (steady cycle)")
    ax2.set_ylabel("material removal rate (cm^3/min)", color="tab:red")
    ax.set_title("Elliptical trochoidal slot (Wagih 2023): chip and removal rate")
    fig.legend(loc="upper left", bbox_to_anchor=(0.12, 0.88))
    fig.tight_layout()
    out = pathlib.Path(out_dir) / "wagih_aspect_ratio.png"
    fig.savefig(out, dpi=120)
    print(out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
