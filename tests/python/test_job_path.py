"""The job, plans, samples and NC programs through the module, against the CLI."""

import math
import pathlib
import tomllib

import numpy as np
import pytest
import trochomill as tm

from conftest import assert_printed, cli_csv, cli_json, run_cli


def test_job_keys_are_the_files(wagih):
    job = tm.Job.from_toml(wagih)
    with open(wagih, "rb") as f:
        assert job.to_dict() == tomllib.load(f)
    assert job.source == str(wagih)
    assert job.feed_rate_mm_per_min > 0 and job.spindle_speed_rpm > 0


def test_set_changes_the_key_and_a_refused_value_changes_nothing(wagih):
    job = tm.Job.from_toml(wagih)
    job.set("path.aspect_ratio", 1.2)
    job.set("tool.tooth_angles", [0, 95, 180, 275])
    d = job.to_dict()
    assert d["path"]["aspect_ratio"] == 1.2
    assert d["tool"]["tooth_angles"] == [0, 95, 180, 275]
    before = job.to_toml()
    with pytest.raises(tm.InputError) as e:
        job.set("path.step", -1.0)
    assert isinstance(e.value, ValueError)
    assert job.to_toml() == before
    # The message is the CLI's for the same --set.
    cli = run_cli("analyze", wagih, "--set", "path.step=-1.0", check=False)
    assert cli.returncode == 2
    assert str(e.value) in cli.stderr
    assert e.value.problems == [str(e.value)]


def test_bad_values_name_the_key(wagih):
    job = tm.Job.from_toml(wagih)
    with pytest.raises(tm.InputError, match="path.step: expected a number"):
        job.set("path.step", "fast")
    with pytest.raises(tm.InputError, match="'step': a job key is section.key"):
        job.set("step", 1.0)
    with pytest.raises(tm.InputError, match="path.step: a dict cannot be a job value"):
        job.set("path.step", {"a": 1})
    with pytest.raises(tm.InputError, match="unknown key"):
        tm.Job.from_toml(wagih, set={"path.stepp": 1.0})
    with pytest.raises(tm.InputError, match="tool.diameter: must be a finite number, got nan"):
        job.set("tool.diameter", float("nan"))


def test_toml_syntax_error_names_line_and_column(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[tool]\ndiameter = 10.0\nteeth = = 4\n")
    with pytest.raises(tm.InputError) as e:
        tm.Job.from_toml(bad)
    assert f"{bad}:3:" in str(e.value)
    cli = run_cli("analyze", bad, check=False)
    assert cli.returncode == 2 and str(e.value) in cli.stderr


def test_missing_file_is_reported_as_the_cli_reports_it(tmp_path):
    missing = tmp_path / "none.toml"
    cli = run_cli("analyze", missing, check=False)
    expected = tm.InputError if cli.returncode == 2 else OSError
    with pytest.raises(expected) as e:
        tm.Job.from_toml(missing)
    assert str(e.value) in cli.stderr


def test_dict_and_text_round_trips_give_the_same_job(wagih):
    job = tm.Job.from_toml(wagih, set={"path.aspect_ratio": 0.9})
    again = tm.Job.from_dict(job.to_dict())
    text = tm.Job.from_text(job.to_toml())
    assert again.to_dict() == job.to_dict() == text.to_dict()
    def body(code):  # the program without its "; job: <source>" header line
        return [line for line in code.splitlines() if not line.startswith("; job:")]

    assert body(tm.plan(again).gcode()) == body(tm.plan(job).gcode()) == body(tm.plan(text).gcode())


def test_from_dict_names_bad_sections_and_keys():
    with pytest.raises(tm.InputError, match="'tool': a section is a dict"):
        tm.Job.from_dict({"tool": 10.0})
    with pytest.raises(tm.InputError, match="tool.diameter"):
        tm.Job.from_dict({"tool": {"diameter": -1.0}})


def test_copy_is_independent(wagih):
    job = tm.Job.from_toml(wagih)
    other = job.copy()
    other.set("path.step", 0.5)
    assert job.to_dict()["path"]["step"] == 1.0 and other.to_dict()["path"]["step"] == 0.5


@pytest.mark.parametrize("dialect", [None, "fanuc", "sinumerik", "grbl", "haas", "mach3"])
def test_gcode_is_the_plan_commands(wagih, dialect):
    path = tm.plan(tm.Job.from_toml(wagih))
    args = ["plan", wagih, "-o", "-"] + (["--dialect", dialect] if dialect else [])
    assert path.gcode(dialect=dialect) == run_cli(*args).stdout


def test_plan_summary_is_the_cli_summary(wagih):
    job = tm.Job.from_toml(wagih)
    path = tm.plan(job)
    line = run_cli("plan", wagih, "-o", "/dev/null").stdout
    # "...: elliptical 20 cycles, path 595.535 mm, time 58.844 s (58.986 s with acceleration)"
    assert f"{path.cycles} cycles" in line
    assert f"path {path.length_mm:.3f} mm" in line
    assert f"time {path.duration_s:.3f} s ({path.time_s():.3f} s with acceleration)" in line
    assert path.cycle_start_s.shape == (path.cycles,)
    assert np.all(np.diff(path.cycle_start_s) > 0)


def test_samples_are_the_path_commands(wagih):
    path = tm.plan(tm.Job.from_toml(wagih))
    s = path.sample(dt_s=0.05)
    cli = cli_csv("path", wagih, "--dt", "0.05")
    for name in ["t_s", "s_mm", "x_mm", "y_mm", "z_mm"]:
        assert_printed(s[name], cli[name], name)
    assert s["rapid"].dtype == np.bool_ and s["feed_mm_per_min"].dtype == np.float64
    # The feed along the path integrates to the programmed time (each sample's segment speed).
    assert np.all(s["feed_mm_per_min"] > 0)
    by_length = path.sample(ds_mm=1.0)
    assert by_length["s_mm"][-1] == pytest.approx(path.length_mm, rel=1e-12)
    with pytest.raises(tm.InputError, match="dt_s or ds_mm, not both"):
        path.sample(dt_s=0.1, ds_mm=1.0)
    with pytest.raises(tm.InputError, match="dt_s must be in"):
        path.sample(dt_s=0.0)


def test_a_program_read_back_is_the_planned_path(wagih, tmp_path):
    job = tm.Job.from_toml(wagih)
    planned = tm.plan(job)
    program = tmp_path / "slot.ngc"
    program.write_text(planned.gcode())
    from_file = tm.read_gcode(program, job=job)
    from_text = tm.read_gcode(program.read_text(), job=job)
    check = cli_json("check-gcode", program)
    # The arcs of the program are fitted to the ellipses within machine.arc_tolerance:
    # lengths agree to a few tolerances over the path; the CLI reads the same program.
    assert from_file.length_mm == pytest.approx(check["path_length_mm"], rel=1e-12)
    assert from_text.length_mm == from_file.length_mm
    assert from_file.length_mm == pytest.approx(planned.length_mm, rel=1e-4)
    assert tm.read_gcode(pathlib.Path(program)).length_mm == from_file.length_mm
    # The analysis of the program is the CLI's analyze --gcode.
    result = tm.analyze(from_file)
    expected = cli_json("analyze", wagih, "--gcode", program)
    result.pop("series")
    result.pop("wall_texture_profiles")
    result.pop("floor_texture_profiles")
    assert result == expected


def test_gcode_errors_name_line_and_column(tmp_path):
    with pytest.raises(tm.InputError, match=r"<text>:2:\d+"):
        tm.read_gcode("G21 G90\nG1 X1 Y2 Q\nM2\n")
    with pytest.raises(tm.InputError, match="read without a job"):
        tm.read_gcode("G21 G90 G1 X1 F100\nG1 X2\nM2\n").gcode()


def test_a_tool_the_table_lacks_is_the_jobs(wagih):
    """G41 D4 with no tool table: without a job the offset is 0 (as LinuxCNC), with one it is
    the job's tool's radius (elliptical.toml: D 10 mm); each said in a warning."""
    text = "G21 G17 G90 G94\nG0 X20 Y-20 Z0\nF500\nG41 D4\nG1 Y0\nG3 X20 Y0 I-20 J0\nG40\nG1 X0\nM2\n"
    alone = tm.read_gcode(text)
    assert any("its diameter is taken as 0" in w for w in alone.warnings)
    job = tm.Job.from_toml(wagih)
    with_job = tm.read_gcode(text, job=job)
    d = job.to_dict()["tool"]["diameter"]
    assert any("the job's tool's, %g mm" % d in w for w in with_job.warnings)
    # The full circle runs a tool radius r inside the programmed one (radius 20 - r): 2 pi r
    # shorter; the entry and exit lines change by less than r each.
    r = d / 2
    assert alone.length_mm - with_job.length_mm > 2 * math.pi * r - 2 * r


def test_a_drawing_reads_as_check_drawing_reads_it():
    root = pathlib.Path(__file__).resolve().parents[2]
    for name, layers in (("examples/curves/part.dxf", None), ("examples/curves/s-curve.svg", ["SLOT"])):
        file = str(root / name)
        d = tm.read_drawing(file, layers=layers)
        args = ["check-drawing", file] + sum((["--layer", l] for l in layers or []), [])
        assert d == cli_json(*args)
    ring = [c for c in tm.read_drawing(str(root / "examples/curves/part.dxf"))["contours"]
            if c["layer"] == "RING"][0]
    # The circle of radius 30 mm: its length and area in closed form (1e-9: arcs are exact).
    assert ring["length_mm"] == pytest.approx(2 * np.pi * 30, rel=1e-9)
    with pytest.raises(tm.InputError) as e:
        tm.read_drawing(str(root / "examples/curves/part.dxf"), layers=["NOPE"])
    assert "no line, arc or curve on layer 'NOPE'" in str(e.value)


def test_a_slot_along_a_curve_plans_as_the_cli_plans_it():
    root = pathlib.Path(__file__).resolve().parents[2]
    job = tm.Job.from_toml(root / "examples/curves/bend.toml")
    path = tm.plan(job)
    cli = run_cli("plan", str(root / "examples/curves/bend.toml"), "-o", "-").stdout
    assert path.gcode() == cli


def test_a_pocket_on_a_stock_mesh_plans_and_proves_as_the_cli():
    # The cored blank ([stock] mesh, FreeCAD's): the same program and the same proof (plan
    # --json) as the CLI's; the first level comes down into the core (its air, the second's
    # none); a slot's plan has no pocket figures.
    root = pathlib.Path(__file__).resolve().parents[2]
    ex = str(root / "examples/pockets/cored.toml")
    path = tm.plan(tm.Job.from_toml(ex))
    assert path.gcode() == run_cli("plan", ex, "-o", "-").stdout
    pocket = path.pocket
    assert pocket == cli_json("plan", ex, "-o", "/dev/null")
    assert pocket["proven"] is True
    assert pocket["plans"] == 2
    assert pocket["open_mm2_by_level"][0] > 200 and pocket["open_mm2_by_level"][1] == 0
    assert pocket["clearing_max_engagement_deg"] <= 53 * 1.02
    assert tm.plan(tm.Job.from_toml(root / "examples/wagih2023/trochoidal.toml")).pocket is None


def test_other_axes_read_as_check_gcode_reports_them():
    """A and W words: each axis's range (A degrees, W mm) as check-gcode --json gives it, and
    the time of the move of A alone at F degrees/min (90 degrees at 180/min: 30 s), which the
    path's duration (its X Y Z motion) leaves out."""
    text = "G21 G90 G94\nG0 X0 Y0 Z5 A0\nG1 X10 F600 W-2\nG1 A90 F180\nG1 A-30 X20 F600\nM2\n"
    p = tm.read_gcode(text)
    assert p.extra_axes == {"A": {"min_deg": -30.0, "max_deg": 90.0},
                            "W": {"min_mm": -2.0, "max_mm": 0.0}}
    assert p.extra_axes_only_time_s == pytest.approx(30.0, rel=1e-12)
    # The path starts at the first position (X0 Y0 Z5): two 10 mm X moves at 600 mm/min.
    assert p.duration_s == pytest.approx(2 * 10 / 600 * 60, rel=1e-12)
    assert tm.read_gcode("G0 X1\nM2\n").extra_axes == {}
