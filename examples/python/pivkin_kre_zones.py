"""Pivkin 2025: K_re = 100 h / r_e over one trochoid cycle with the cutting-mechanism zones
shaded (CZI ploughing, CZII mixed, CZIII cutting), the exact chip model against the paper's
published one. Writes pivkin_kre_zones.png.

    PYTHONPATH=build/python python3 examples/python/pivkin_kre_zones.py [OUTPUT_DIR]
"""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import trochomill as tm  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
ZONE_COLOURS = {1: ("#f4a582", "CZI"), 2: ("#fddbc7", "CZII"), 3: ("#d1e5f0", "CZIII")}


def main(out_dir):
    job = tm.Job.from_toml(HERE.parent / "pivkin2025" / "trochoidal.toml")
    exact = tm.mechanism(job, model="exact")
    published = tm.mechanism(job, model="pivkin2025")
    fig, ax = plt.subplots(figsize=(8, 4.2))
    theta, zone = exact["theta_deg"], exact["zone"]
    # Shade each run of one zone.
    edges = np.flatnonzero(np.diff(zone)) + 1
    for lo, hi in zip(np.r_[0, edges], np.r_[edges, len(zone)]):
        if zone[lo] in ZONE_COLOURS:
            colour, _ = ZONE_COLOURS[zone[lo]]
            ax.axvspan(theta[lo], theta[hi - 1], color=colour, lw=0)
    for z, (colour, name) in ZONE_COLOURS.items():
        share = exact["zone_share"][name]
        ax.fill_between([], [], color=colour, label=f"{name} ({100 * share:.0f} % of cutting)")
    ax.plot(theta, exact["k_re_pct"], color="black", label="K_re, exact chip")
    ax.plot(published["theta_deg"], published["k_re_pct"], "--", color="tab:purple",
            label="K_re, Pivkin 2025 chip model")
    th = exact["thresholds_pct"]
    for key in ("czi_max", "czii_max"):
        ax.axhline(th[key], color="grey", lw=0.8, ls=":")
    ax.set_xlabel("trochoid angle theta (deg)")
    ax.set_ylabel("K_re = 100 h / r_e (%)")
    ax.set_title(f"Cutting mechanism over a cycle (r_e {1000 * exact['edge_radius_mm']:.1f} um)")
    ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    out = pathlib.Path(out_dir) / "pivkin_kre_zones.png"
    fig.savefig(out, dpi=120)
    print(out)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
