"""Every model function against the CLI for the same job: the JSON documents key for key and
value for value, the series to the last digit the CLI prints."""

import json
import wave

import numpy as np
import pytest
import trochomill as tm

from conftest import assert_printed, cli_csv, cli_json, run_cli

# A small dexel simulation of the Bergmann example: a 6 mm slot at a 0.05 mm spacing and 120
# steps per revolution (the example's 0.005 mm and 600 take minutes).
SMALL_SIM = {"simulation.resolution": 0.05, "simulation.steps_per_rev": 120, "slot.length": 6.0}


def sets(d):
    out = []
    for k, v in d.items():
        out += ["--set", f"{k}={v}"]
    return out


def without(d, *keys):
    return {k: v for k, v in d.items() if k not in keys}


@pytest.mark.parametrize("overrides", [{}, {"path.aspect_ratio": 1.25, "path.step": 0.8}])
def test_analyze_is_the_clis(wagih, overrides):
    job = tm.Job.from_toml(wagih, set=overrides)
    result = tm.analyze(job)
    series = result.pop("series")
    walls = result.pop("wall_texture_profiles")
    floor = result.pop("floor_texture_profiles")
    assert result == cli_json("analyze", wagih, *sets(overrides))
    # The predicted walls' and floor's Ra is the mean |R| of the profile they were evaluated on.
    for side in ("left", "right"):
        r = walls[side]["roughness_mm"]
        assert np.mean(np.abs(r)) == pytest.approx(result[f"ra_{side}_mm"], rel=1e-12)
        assert len(walls[side]["x_mm"]) == len(r) == len(walls[side]["waviness_mm"])
    for line, key in (("left", "ra_floor_left_mm"), ("middle", "ra_floor_mm"),
                      ("right", "ra_floor_right_mm")):
        r = floor[line]["roughness_mm"]  # heights about their mean (ISO 21920-2)
        assert np.mean(np.abs(r - np.mean(r))) == pytest.approx(result[key], rel=1e-9)
    assert floor["middle"]["line_x_mm"] == 0.0
    csv = cli_csv("analyze", wagih, *sets(overrides))
    for name in ["t_s", "x_mm", "y_mm", "z_mm", "engagement_deg", "h_max_mm", "teeth_in_cut",
                 "mrr_mm3_per_min"]:
        assert_printed(series[name], csv[name], name)
    n = len(series["t_s"])
    for name, a in series.items():
        assert a.shape == (n,), name
        assert a.dtype == (np.int32 if name == "teeth_in_cut" else np.float64), name
    # The largest chip of the program is the series' largest (the radial chip, no plunge).
    assert result["h_max_mm"] == pytest.approx(series["h_max_mm"].max(), rel=1e-12)


def test_analyze_leaves_out_the_parts_not_asked_for(wagih):
    job = tm.Job.from_toml(wagih)
    full = tm.analyze(job)
    walls_keys = ("waviness_", "ra_left", "ra_right", "rz_left", "rz_right", "wa_left",
                  "wa_right", "wt_left", "wt_right", "lambda_c_left", "lambda_c_right",
                  "wall_peak", "cycle_h_max_tooth", "cycle_h_max_per_tooth",
                  "cycle_chip_translation", "bottom_imprint", "performance_index_")
    for parts in ({"floor": False}, {"walls": False, "floor": False},
                  {"force": False}, {"walls": False, "floor": False, "force": False}):
        some = tm.analyze(job, **parts)
        assert some.pop("floor_texture_profiles") == {} or parts.get("floor", True)
        assert (some.pop("wall_texture_profiles") == {}) == (not parts.get("walls", True))
        left_out = 0
        for key, value in some.items():
            if key in ("series", "performance_index_note"):
                continue
            gone = ((not parts.get("floor", True) and "floor" in key)
                    or (not parts.get("walls", True) and key.startswith(walls_keys))
                    or (not parts.get("force", True)
                        and key in ("cycle_force_max_predicted_n", "performance_index"))
                    or (not parts.get("walls", True) and key == "performance_index"))
            if gone:
                assert value is None and full[key] is not None, key
                left_out += 1
            else:  # the same code on the same input: equal to the bit
                assert value == full[key], key
        assert left_out >= 2, parts


def test_analyze_a_job_without_a_steady_cycle(wagih):
    job = tm.Job.from_toml(wagih, set={"path.type": "linear", "path.aspect_ratio": 1.0})
    result = tm.analyze(job)
    assert result["cycle_h_max_mm"] is None
    result.pop("series")
    result.pop("floor_texture_profiles")
    walls = result.pop("wall_texture_profiles")
    for side in ("left", "right"):  # profiles exactly where the JSON has a wall texture
        assert (side in walls) == (result[f"ra_{side}_mm"] is not None)
    assert result == cli_json("analyze", wagih, "--set", "path.type=linear",
                              "--set", "path.aspect_ratio=1.0")


def test_compare_columns_are_the_clis_points(wagih):
    job = tm.Job.from_toml(wagih, set={"slot.length": 8.0})
    vary = {"path.aspect_ratio": [0.8, 1.2], "path.step": [0.8, 1.0]}
    cols = tm.compare(job, vary, threads=2)
    cli = cli_json("compare", wagih, "--set", "slot.length=8.0", "--vary",
                   "path.aspect_ratio=0.8,1.2", "--vary", "path.step=0.8,1.0")
    points = cli["points"]
    assert list(cols["path.aspect_ratio"]) == [0.8, 0.8, 1.2, 1.2]  # the first varies slowest
    assert list(cols["path.step"]) == [0.8, 1.0, 0.8, 1.0]
    assert list(cols["ok"]) == [p["ok"] for p in points] == [True] * 4
    for key in ["h_max_mm", "cycle_time_s", "mrr_total_mm3_per_min", "machining_time_s"]:
        assert list(cols[key]) == [p["metrics"][key] for p in points], key
    # The same grid on one thread: the same columns.
    one = tm.compare(job, vary, threads=1)
    for key, col in cols.items():
        if key == "error":
            assert one[key] == col
        else:
            np.testing.assert_array_equal(one[key], col, err_msg=key)  # NaN where None


def test_compare_columns_are_keyed_by_name(wagih):
    # A job that sets a varied key itself: each point holds both overrides, the study's last;
    # every column is one entry a point (its key appended twice once shifted the rows).
    job = tm.Job.from_toml(wagih, set={"slot.length": 8.0, "path.step": 0.9})
    cols = tm.compare(job, {"path.step": [0.8, 1.0], "path.aspect_ratio": [1.0, 1.2]})
    n = len(cols["ok"])
    assert n == 4
    for key, col in cols.items():
        assert len(col) == n, key
    assert list(cols["path.step"]) == [0.8, 0.8, 1.0, 1.0]
    cli = cli_json("compare", wagih, "--set", "slot.length=8.0", "--set", "path.step=0.9",
                   "--vary", "path.step=0.8,1.0", "--vary", "path.aspect_ratio=1.0,1.2")
    assert list(cols["cycle_time_s"]) == [p["metrics"]["cycle_time_s"] for p in cli["points"]]


def test_compare_records_a_failed_point(wagih):
    cols = tm.compare(tm.Job.from_toml(wagih, set={"slot.length": 8.0}), {"path.step": [1.0, -1.0]})
    assert list(cols["ok"]) == [True, False]
    assert "path.step" in cols["error"][1] and cols["error"][0] == ""
    assert np.isnan(cols["h_max_mm"][1]) and cols["h_max_mm"][0] > 0


@pytest.mark.parametrize("model", ["exact", "pivkin2025"])
def test_mechanism_is_the_clis(pivkin, model):
    result = tm.mechanism(tm.Job.from_toml(pivkin), model=model)
    cli = cli_json("mechanism", pivkin, "--model", model)
    for key, value in cli.items():
        if isinstance(value, list):
            np.testing.assert_array_equal(result[key], value, err_msg=key)
        else:
            assert result[key] == value, key
    csv = cli_csv("mechanism", pivkin, "--model", model)
    for name in ["theta_deg", "t_s", "h_mm", "psi_deg", "teeth_in_contact", "gamma_k_deg",
                 "kappa_deg", "k_re_pct", "zone"]:
        assert_printed(result[name], csv[name], name)
    assert result["zone"].dtype == np.int32
    # K_re is 100 h / r_e (Pivkin 2025 Eq. 1) for a sharp-free new tool.
    np.testing.assert_allclose(result["k_re_pct"], 100 * result["h_mm"] / result["edge_radius_mm"],
                               rtol=1e-12)


def test_mechanism_with_wear_is_the_clis(pivkin):
    result = tm.mechanism(tm.Job.from_toml(pivkin), flank_wear_mm=0.1)
    cli = cli_json("mechanism", pivkin, "--wear", "0.1")
    assert result["flank_wear_mm"] == 0.1
    np.testing.assert_array_equal(result["k_re_pct"], cli["k_re_pct"])


@pytest.mark.parametrize("feed", [False, True])
def test_recommend_is_the_clis(pivkin, feed):
    result = tm.recommend(tm.Job.from_toml(pivkin), share=0.6, feed=feed)
    cli = cli_json("recommend", pivkin, "--share", "0.6", *(["--feed"] if feed else []))
    assert result == cli
    assert "60 % of the cutting part in CZIII" in result["explanation"]


def test_recommend_plunger_is_the_clis(pivkin):
    result = tm.recommend(tm.Job.from_toml(pivkin), criterion="plunger", plunger_share=0.1)
    cli = cli_json("recommend", pivkin, "--criterion", "plunger", "--plunger-share", "0.1")
    assert result == cli
    assert result["criterion"] == "plunger" and result["plunger_first_half_share"] <= 0.1
    with pytest.raises(tm.InputError, match="plunger_share"):
        tm.recommend(tm.Job.from_toml(pivkin), criterion="plunger", plunger_share=1.5)


def test_simulate_is_the_clis(bergmann, tmp_path):
    job = tm.Job.from_toml(bergmann, set=SMALL_SIM)
    result = tm.simulate(job, cycles=(1, 2))
    out = tmp_path / "sim"
    cli = cli_json("simulate", bergmann, *sets(SMALL_SIM), "--cycles", "1:2", "--out", out)
    timing = ("wall_time_s", "window_wall_s", "pre_roll_wall_s", "dexel_updates_per_s",
              "memory_mb", "memory_peak_mb", "memory_estimate_mb", "pre_roll_cpu_s",
              "window_cpu_s", "pre_roll_utilisation", "window_utilisation", "threads")
    # The memory estimate includes the dense chip map the module returns (as --out's HDF5).
    assert without(result, "series", "chip_map", "surface", "floor", "floor_note", *timing) == \
        without(cli, *timing)
    # One cycle of a 50 mm wide slot leaves no floor cut across it: no floor.x3p from the CLI
    # (it says why), no floor map here, with the same reason.
    assert not (out / "floor.x3p").exists()
    assert result["floor"] is None
    assert result["floor_note"].startswith("floor: no two rows of the workpiece are cut")
    series = result["series"]
    import csv as csvmod
    with open(out / "series.csv") as f:
        rows = list(csvmod.reader(f))
    cols = {name: [r[i] for r in rows[1:]] for i, name in enumerate(rows[0])}
    assert_printed(series["t_s"], cols["t_s"], "t_s")
    for axis, name in enumerate(["x_mm", "y_mm", "z_mm"]):
        assert_printed(series["tip_mm"][:, axis], cols[name], name)
    for k in range(2):
        assert_printed(series["removed_mm3"][:, k], cols[f"removed_tooth{k}_mm3"], f"tooth {k}")
    assert_printed(series["h_max_mm"], cols["h_max_mm"], "h_max_mm")
    assert_printed(series["engaged_segments"], cols["engaged_segments"], "engaged_segments")
    # The removed volume is the steps' sum; the chip map's volumes are the steps' volumes.
    assert series["removed_mm3"].sum() == pytest.approx(result["removed_volume_mm3"], rel=1e-9)
    chips = result["chip_map"]
    steps = len(series["t_s"])
    assert chips["h_mm"].dtype == np.float32 and chips["h_mm"].shape[:2] == (steps, 2)
    np.testing.assert_array_equal(chips["removed_mm3"], series["removed_mm3"])
    np.testing.assert_array_equal(chips["t_s"], series["t_s"])
    assert chips["h_mm"].max() == pytest.approx(result["h_max_mm"], rel=1e-6)  # float32
    surface = result["surface"]
    v, f = surface["vertices_mm"], surface["faces"]
    assert v.shape[1] == 3 and f.shape[1] == 3 and f.dtype == np.uint32
    assert f.max() < len(v)
    # The surface lies between the stock's bottom and its top (z = 0), cut into the slot.
    assert v[:, 2].max() <= 1e-9 and v[:, 2].min() >= surface["bottom_mm"] - 1e-9
    assert v[:, 2].min() < -0.9  # the 1 mm deep slot


def test_forces_are_the_clis(bergmann):
    job = tm.Job.from_toml(bergmann, set=SMALL_SIM)
    result = tm.forces(job, fast=True, from_s=45.6, to_s=45.9)
    window = ["--fast", "--from", "45.6", "--to", "45.9"]
    cli = cli_json("forces", bergmann, *sets(SMALL_SIM), *window)
    timing = ("chips_wall_s", "forces_wall_s")
    assert without(result, "series", *timing) == without(cli, *timing)
    csv = cli_csv("forces", bergmann, *sets(SMALL_SIM), *window)
    s = result["series"]
    for name in ["t_s", "f_x_n", "f_y_n", "f_z_n", "f_resultant_n", "torque_nm", "power_w"]:
        assert_printed(s[name], csv[name], name)
    for k in range(2):
        assert_printed(s["tooth_f_x_n"][:, k], csv[f"tooth{k}_f_x_n"], f"tooth {k}")
    # The teeth's forces add up to the tool's.
    np.testing.assert_allclose(s["tooth_f_x_n"].sum(axis=1), s["f_x_n"], rtol=1e-12, atol=1e-9)
    assert result["f_resultant_max_n"] == pytest.approx(s["f_resultant_n"].max(), rel=1e-12)


def without_material(job, tmp_path):
    """The job file without its [material] section (the examples carry one)."""
    text = open(job).read()
    out = tmp_path / "no-material.toml"
    out.write_text(text[: text.index("[material]")])
    return out


def test_forces_need_a_material(wagih, tmp_path):
    with pytest.raises(tm.InputError, match="no \\[material\\] force model"):
        tm.forces(tm.Job.from_toml(without_material(wagih, tmp_path)))


def test_calibrate_is_the_clis(bergmann, tmp_path):
    job = tm.Job.from_toml(bergmann, set=SMALL_SIM)
    measured = tmp_path / "forces.csv"
    window = ["--fast", "--from", "45.6", "--to", "45.9"]
    run_cli("forces", bergmann, *sets(SMALL_SIM), *window, "--csv", measured)
    data = np.genfromtxt(measured, delimiter=",", names=True)
    f = np.column_stack([data["f_x_n"], data["f_y_n"], data["f_z_n"]])
    # The CSV's printed values are the measurement both fit.
    result = tm.calibrate(job, data["t_s"], f, fast=True)
    toml_block = result.pop("material_toml")
    cli = cli_json("calibrate", bergmann, *sets(SMALL_SIM), "--measured", measured, "--fast")
    assert result == cli
    assert "[material]" in toml_block
    with pytest.raises(tm.InputError, match="shape"):
        tm.calibrate(job, data["t_s"], f[:, :2])
    with pytest.raises(tm.InputError, match="times must increase"):
        tm.calibrate(job, data["t_s"][::-1].copy(), f)


def read_float_wav(path):
    """A mono IEEE-float WAV (format 3) as float64, read chunk by chunk."""
    raw = path.read_bytes()
    assert raw[:4] == b"RIFF" and raw[8:12] == b"WAVE"
    pos, fmt, data = 12, None, None
    while pos < len(raw):
        cid, size = raw[pos:pos + 4], int.from_bytes(raw[pos + 4:pos + 8], "little")
        body = raw[pos + 8:pos + 8 + size]
        if cid == b"fmt ":
            fmt = body
        elif cid == b"data":
            data = body
        pos += 8 + size + (size & 1)
    assert int.from_bytes(fmt[0:2], "little") in (3, 0xFFFE)
    rate = int.from_bytes(fmt[4:8], "little")
    return np.frombuffer(data, dtype="<f4").astype(np.float64), rate


def test_synth_signal_is_the_clis(pivkin, tmp_path):
    job = tm.Job.from_toml(pivkin)
    sig = tm.synth_signal(job, rate_hz=40000, cycles=3, seed=7)
    wav = tmp_path / "s.wav"
    run_cli("synth-signal", pivkin, "--rate", "40000", "--cycles", "3", "--seed", "7", "-o", wav)
    samples, rate = read_float_wav(wav)
    assert rate == 40000 and sig["rate_hz"] == 40000 and sig["cycles"] == 3
    # The WAV holds float32: the module's float64 samples rounded to float32 are its samples.
    np.testing.assert_array_equal(sig["samples"].astype(np.float32).astype(np.float64), samples)


def test_monitor_is_the_clis(pivkin, tmp_path):
    job = tm.Job.from_toml(pivkin)
    sig = tm.synth_signal(job, rate_hz=40000, cycles=4, wear_drift=0.5)
    x = sig["samples"]
    path = tmp_path / "s.csv"
    np.savetxt(path, x, fmt="%.17g")  # read back to the same doubles
    result = tm.monitor(x, 40000, job=job, start_s=sig["start_s"])
    windows = result.pop("windows")
    cli = cli_json("monitor", path, "--rate", "40000", "--job", pivkin, "--start", sig["start_s"])
    assert without(result, "signal") == without(cli, "signal")
    csv = cli_csv("monitor", path, "--rate", "40000", "--job", pivkin, "--start", sig["start_s"])
    for name in ["t_s", "rms_low", "rms_high", "k_f"]:
        assert_printed(windows[name], csv[name], name)
    assert result["warnings"] == []
    # Without a job the bands can be set as keys; a band above the Nyquist rate is refused.
    free = tm.monitor(x, 40000, set={"monitor.window": 0.002})
    assert free["windows"]["t_s"][1] - free["windows"]["t_s"][0] == pytest.approx(0.002)
    with pytest.raises(tm.InputError, match="rate / 2"):
        tm.monitor(x[:4000], 10000)
    with pytest.raises(tm.InputError, match=r"samples\[3\] is nan"):
        tm.monitor(np.array([0, 1, 2, np.nan, 4.0]), 40000)


def test_spectrum_is_the_clis(pivkin, tmp_path):
    sig = tm.synth_signal(tm.Job.from_toml(pivkin), rate_hz=40000, cycles=2)
    path = tmp_path / "s.csv"
    np.savetxt(path, sig["samples"], fmt="%.17g")
    sp = tm.spectrum(sig["samples"], 40000, nfft=1024, spectrogram=True)
    csv = cli_csv("spectrum", path, "--rate", "40000", "--nfft", "1024")
    assert_printed(sp["f_hz"], csv["f_hz"], "f_hz")
    assert_printed(sp["psd_per_hz"], csv["psd_per_hz"], "psd_per_hz")
    g = sp["spectrogram"]
    assert g["db"].shape == (len(g["t_s"]), len(g["f_hz"]))
    long_form = cli_csv("spectrum", path, "--rate", "40000", "--nfft", "1024", option="--spectrogram")
    assert_printed(g["db"].ravel(), long_form["db"], "db")  # frame by frame, bins within
    # Parseval: the PSD integrates to the signal's variance (Welch with a Hann window and
    # density scaling; 2 % for the averaging over segments of a non-stationary signal).
    df = sp["f_hz"][1] - sp["f_hz"][0]
    assert np.sum(sp["psd_per_hz"]) * df == pytest.approx(np.var(sig["samples"]), rel=0.02)


def test_keys_and_materials_are_the_clis():
    assert tm.keys() == cli_json_plain("keys")
    assert tm.materials() == cli_json_plain("materials")
    assert any(k["section"] == "path" and k["key"] == "step" and k["unit"] == "mm" for k in tm.keys())


def cli_json_plain(*args):
    import json
    return json.loads(run_cli(*args, "--json").stdout)


def test_schedule_feed_is_plan_feed_schedule(wagih, tmp_path):
    job = tm.Job.from_toml(wagih)
    fs = tm.schedule_feed(job, max_feed_mm_per_min=1500.0)
    out = tmp_path / "fs.ngc"
    p = run_cli("plan", wagih, "-o", out, "--feed-schedule", "--max-feed", "1500")
    assert fs["path"].gcode() == out.read_text()
    # "feed schedule: h_max 0.07500 -> 0.07501 mm (target 0.075), time 58.844 -> 27.377 s"
    assert f"h_max {fs['h_max_before_mm']:.5f} -> {fs['h_max_after_mm']:.5f} mm" in p.stderr
    assert f"time {fs['time_before_s']:.3f} -> {fs['time_after_s']:.3f} s" in p.stderr
    assert fs["time_after_s"] < fs["time_before_s"]
    feeds = fs["piece_feed_mm_per_min"]
    assert feeds.max() <= 1500.0 and feeds.min() >= 0.1 * job.feed_rate_mm_per_min
    # Where no limit holds a piece, its largest chip is the target, the job's f_z = f_r / (n Z):
    # three quarters of such pieces come within 3 % on the Wagih paths (docs/PERFORMANCE.md),
    # so their median must.
    free = fs["piece_limit"] == 0
    assert free.any()
    fz = job.feed_rate_mm_per_min / (job.spindle_speed_rpm * job.to_dict()["tool"]["teeth"])
    assert np.median(np.abs(fs["piece_h_max_mm"][free] / fz - 1)) < 0.03
    with pytest.raises(tm.InputError):
        tm.schedule_feed(job, h_max_mm=-1.0)


def test_feed_limits_from_the_machine(wagih, tmp_path):
    job = tm.Job.from_toml(wagih, set={"machine.max_feed": 1500.0, "machine.min_feed": 100.0})
    from_keys = tm.schedule_feed(job)
    given = tm.schedule_feed(tm.Job.from_toml(wagih), max_feed_mm_per_min=1500.0,
                             min_feed_mm_per_min=100.0)
    np.testing.assert_array_equal(from_keys["piece_feed_mm_per_min"], given["piece_feed_mm_per_min"])
    assert from_keys["piece_feed_mm_per_min"].max() == 1500.0  # the air moves, at the max feed
    out = tmp_path / "fs.ngc"
    run_cli("plan", wagih, "-o", out, "--feed-schedule", "--set", "machine.max_feed=1500.0",
            "--set", "machine.min_feed=100.0")  # as typed: the header records the keys
    assert from_keys["path"].gcode() == out.read_text()
    with pytest.raises(tm.InputError, match="machine.min_feed: must not exceed max_feed"):
        job.set("machine.min_feed", 2000.0)


def report_data(html):
    """The data document a report page embeds."""
    start = html.index('<script type="application/json" id="trochomill-data">')
    start = html.index(">", start) + 1
    end = html.index("</script>", start)
    return json.loads(html[start:end].replace("<\\/", "</"))


def test_report_is_the_clis_page(bergmann, tmp_path):
    """The same parts and numbers as `trochomill report` (the document but for how the job
    and the command are recorded), written atomically where asked."""
    ex = bergmann
    job = tm.Job.from_toml(ex)
    out = tmp_path / "py.html"
    html = tm.report(job, out, cycles=(3, 4))
    assert out.read_text() == html
    cli_out = tmp_path / "cli.html"
    run_cli("report", ex, "--cycles", "3:4", "-o", cli_out)
    a, b = report_data(html), report_data(cli_out.read_text())
    for doc in (a, b):
        for k in ("command", "job_text", "job_file"):
            doc.pop(k)
    assert a == b
    assert a["forces"]["worn"]["label"] == "state 1 (VB 0.15 mm)"


def test_report_refuses_bad_requests(pivkin, tmp_path):
    job = tm.Job.from_toml(pivkin)
    with pytest.raises(tm.InputError, match="unknown item; allowed: mechanism, forces, simulate"):
        tm.report(job, parts=["plots"])
    with pytest.raises(tm.InputError, match="needs start_s"):
        tm.report(job, signal=np.zeros(1000), rate_hz=100000.0)
    with pytest.raises(tm.InputError, match="no \\[material\\] force model"):
        tm.report(tm.Job.from_toml(without_material(pivkin, tmp_path)), parts=["forces"])
    # A study whose every point fails is refused, as the CLI refuses it (nothing written).
    out = tmp_path / "r.html"
    with pytest.raises(tm.InputError, match="report vary: every point of the study failed"):
        tm.report(job, str(out), vary={"path.step": [-1.0, -2.0]})
    assert not out.exists()
    # A key without values is refused (it crashed the process).
    with pytest.raises(tm.InputError, match="vary path.step: no values to take"):
        tm.report(job, str(out), vary={"path.step": []})
    with pytest.raises(tm.InputError, match="vary path.step: no values to take"):
        tm.compare(job, {"path.step": []})


def test_optimize_feed_is_the_cli(wagih, tmp_path):
    """optimize_feed returns what `trochomill optimize-feed` writes: the same program and
    summary; its series re-read: the after feeds within the limits, chips at most 3 % over
    the target (docs/models.md section 15)."""
    text = wagih.read_text().replace('dialect = "sinumerik"', 'dialect = "linuxcnc"')
    job_file = tmp_path / "w.toml"
    job_file.write_text(text)
    prog = tmp_path / "w.ngc"
    run_cli("plan", job_file, "-o", prog)
    out = tmp_path / "fast.ngc"
    summary = tmp_path / "s.json"
    run_cli("optimize-feed", prog, "--job", job_file, "-o", out, "--json", summary,
            "--max-feed", "1500")
    job = tm.Job.from_toml(job_file)
    r = tm.optimize_feed(str(prog), job, max_feed_mm_per_min=1500.0)
    assert r["text"] == out.read_text()
    cli = json.loads(summary.read_text())
    assert r["time_after_s"] == pytest.approx(cli["time_after_s"], rel=1e-12)
    assert r["time_after_s"] < 0.7 * r["time_before_s"]
    after = r["after"]
    # A rapid's samples have no feed (NaN); its first sample may still carry a chip, the one
    # made over the tooth pass before it on the last cut (PathChips' from_*): at most one
    # such sample per rapid, the rest of the cutting samples fed within the limit.
    feed = after["feed_mm_per_min"]
    cutting = after["h_max_mm"] > 0
    on_rapid = cutting & np.isnan(feed)
    assert np.all(~on_rapid[1:] | ~np.isnan(feed[:-1]) | ~cutting[:-1])
    assert feed[cutting & ~on_rapid].max() <= 1500.0
    fz = job.feed_rate_mm_per_min / (job.spindle_speed_rpm * job.to_dict()["tool"]["teeth"])
    assert after["h_max_mm"].max() <= 1.03 * fz
    with pytest.raises(tm.InputError):
        tm.optimize_feed(str(prog), job, h_max_mm=-1.0)


def test_optimize_feed_stock_mesh_and_engine(tmp_path):
    """optimize_feed's engine and stock as the CLI's --engine and --stock: a block as an ASCII
    STL (12 facets) ending at y = 10 under a straight slot: the same program as the CLI's with
    either engine, the summary naming the engine; a bad engine is an InputError."""
    job_file = tmp_path / "j.toml"
    job_file.write_text(
        "[tool]\ndiameter = 10\nteeth = 4\n[slot]\nwidth = 10\nlength = 20\ndepth = 3\n"
        "[path]\ntype = \"linear\"\nstep = 1\n[cutting]\nfeed_rate = 600\n"
        "spindle_speed = 2000\n[machine]\ndialect = \"linuxcnc\"\n[simulation]\n"
        "resolution = 0.1\nsteps_per_rev = 24\n")
    prog = tmp_path / "p.ngc"
    prog.write_text("G21 G90 G17 G94\nG0 X0 Y-8 Z5\nG1 Z-1 F600\nG1 Y20\nG0 Z5\nM2\n")
    lo, hi = (-8.0, 0.0, -3.0), (8.0, 10.0, 0.0)
    corner = [(hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2])
              for k in range(8)]
    facets = []
    for q in [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]:
        for t in [(q[0], q[1], q[2]), (q[0], q[2], q[3])]:
            facets.append("facet normal 0 0 0\nouter loop\n" +
                          "".join("vertex %g %g %g\n" % corner[k] for k in t) +
                          "endloop\nendfacet\n")
    stl = tmp_path / "stock.stl"
    stl.write_text("solid s\n" + "".join(facets) + "endsolid s\n")
    job = tm.Job.from_toml(job_file)
    for engine in ["kernel", "sim"]:
        out = tmp_path / ("out-%s.ngc" % engine)
        run_cli("optimize-feed", prog, "--job", job_file, "-o", out, "--engine", engine,
                "--stock", stl, "--rounds", "2")
        r = tm.optimize_feed(str(prog), job, engine=engine, stock=str(stl), rounds=2)
        assert r["engine"] == engine
        assert r["text"] == out.read_text()
    with pytest.raises(tm.InputError, match="engine"):
        tm.optimize_feed(str(prog), job, engine="gpu")
    # The sim engine's memory estimate is checked before the boards are made, as the CLI's
    # --memory-limit does; the message names the keyword.
    with pytest.raises(tm.InputError, match="or raise memory_limit_gb"):
        tm.optimize_feed(str(prog), job, engine="sim", stock=str(stl), memory_limit_gb=1e-6)
    with pytest.raises(tm.InputError, match="memory_limit_gb"):
        tm.optimize_feed(str(prog), job, memory_limit_gb=-1.0)
