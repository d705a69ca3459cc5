"""Surface texture through the module: the CLI's numbers for the same profile, the evaluated
R and W profiles, closed forms for an areal surface, and a simulated floor."""

import numpy as np
import pytest
import trochomill as tm

from conftest import cli_json

DX = 0.001  # mm


def two_waves(n=8000):
    """2 um at 0.1 mm wavelength (roughness) on 1 um at 2 mm (waviness)."""
    x = np.arange(n) * DX
    return x, 0.002 * np.sin(2 * np.pi * x / 0.1) + 0.001 * np.sin(2 * np.pi * x / 2.0)


def test_profile_texture_is_the_clis(tmp_path):
    x, z = two_waves()
    csv = tmp_path / "p.csv"
    np.savetxt(csv, np.column_stack([x, z]), delimiter=",", header="x_mm,z_mm", comments="",
               fmt="%.17g")
    t = tm.texture_profile(z, DX)
    profile = t.pop("profile")
    cli = cli_json("texture", csv)["surfaces"][0]
    assert t == cli
    # R and W are the profile split by the filter: together the input over the evaluation
    # length (the residual is z less the mean line: equal to rounding).
    first = int(round(profile["x_mm"][0] / DX))
    n = len(profile["x_mm"])
    assert n * DX == pytest.approx(t["evaluation_length_mm"], rel=1e-9)
    np.testing.assert_allclose(profile["roughness_mm"] + profile["waviness_mm"], z[first:first + n],
                               rtol=0, atol=1e-15)
    # Rq is the R profile's root mean square about the mean line (ISO 21920-2).
    assert np.sqrt(np.mean(profile["roughness_mm"] ** 2)) == pytest.approx(t["rq_mm"], rel=1e-12)
    # The 0.1 mm wave is roughness at lambda_c 0.8 mm: Ra of a sinusoid of amplitude A is
    # 2A / pi; the filter passes 99.6 % of it (exp(-pi (alpha 0.1 / 0.8)^2) of the mean line).
    assert t["lambda_c_mm"] == 0.8
    assert t["ra_mm"] == pytest.approx(2 * 0.002 / np.pi, rel=0.01)


def test_profile_texture_options_and_errors():
    _, z = two_waves()
    given = tm.texture_profile(z, DX, lambda_c_mm=0.25, lambda_s_mm=0.0025, robust=True)
    assert given["lambda_c_mm"] == 0.25 and given["lambda_c_source"] == "given"
    assert given["lambda_s_mm"] == 0.0025
    with pytest.raises(tm.InputError, match="cut-off must be between two sample spacings"):
        tm.texture_profile(z, DX, lambda_c_mm=0.001)
    with pytest.raises(tm.InputError, match=r"z_mm\[2\] is inf"):
        tm.texture_profile([0.0, 1.0, np.inf, 2.0], DX)


def test_areal_texture_of_a_sinusoidal_surface():
    # z = A sin(2 pi x / lambda) on a 2 x 2 mm map, 20 whole periods of 20 samples: with no
    # form removed the S-F surface is the map about its mean (0): Sa = mean |z|, Sq = A /
    # sqrt 2 (exact for whole periods), Sp = Sv = A sin(9 pi / 10)... i.e. the sample extremes,
    # Ssk = 0 (by symmetry, to rounding).
    a, lam, d = 0.001, 0.1, 0.005
    x = np.arange(400) * d
    z = np.tile(a * np.sin(2 * np.pi * x / lam), (400, 1))
    t = tm.texture_areal(z, d, d, l_mm=0.8, form="none")
    sf, sl = t["sf"], t["sl"]
    assert sf["sa_mm"] == pytest.approx(np.mean(np.abs(z)), rel=1e-12)
    assert sf["sq_mm"] == pytest.approx(a / np.sqrt(2), rel=1e-12)
    assert sf["sz_mm"] == pytest.approx(z.max() - z.min(), rel=1e-12)
    assert abs(sf["ssk"]) < 1e-9
    # The L-filter at 0.8 mm passes the 0.1 mm wave (its mean surface transmits
    # exp(-pi (alpha 0.8 / 0.1)^2) ~ 1e-38 of it); the renormalised edges of a 2 mm map
    # shift Sq by under 1 %.
    assert t["l_filter_mm"] == 0.8 and t["l_filter_source"] == "given"
    assert sl["sq_mm"] == pytest.approx(a / np.sqrt(2), rel=0.01)
    # The texture runs along x only: the autocorrelation decays across the waves (Sal about
    # a quarter wavelength), not along them (no Str).
    assert sl["sal_mm"] == pytest.approx(lam / 4, rel=0.2)
    assert sl["str"] is None
    with pytest.raises(tm.InputError, match="form 'cone'"):
        tm.texture_areal(z, d, d, form="cone")
    with pytest.raises(tm.InputError, match="2-D array"):
        tm.texture_areal(z[0], d, d)


def test_a_simulated_floor_is_a_height_map(wagih):
    # The Wagih slot's floor in one cycle at a coarse spacing: the floor map the simulation
    # returns, evaluated as the CLI evaluates floor.x3p.
    job = tm.Job.from_toml(wagih, set={"simulation.resolution": 0.05, "slot.length": 4.0,
                                       "simulation.steps_per_rev": 60})
    sim = tm.simulate(job, cycles=(1, 3))
    floor = sim["floor"]
    assert floor is not None, sim["floor_note"]
    ny, nx = floor["z_mm"].shape
    assert floor["dx_mm"] == floor["dy_mm"] == 0.05 and nx >= 2 and ny >= 2
    # The floor lies at the slot's depth (6 mm), within the dexel spacing.
    assert np.median(floor["z_mm"]) == pytest.approx(-6.0, abs=0.05)
    t = tm.texture_areal(floor["z_mm"], floor["dx_mm"], floor["dy_mm"], l_mm=0.25)
    assert t["sl"]["sq_mm"] >= 0
