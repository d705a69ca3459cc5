"""trochomill: trochoidal milling from Python.

Plan trochoidal slot paths, read NC programs, and predict what they do: engagement and chip
thickness (Wagih 2023), cutting-mechanism zones (Pivkin 2025), tri-dexel material removal and
forces (Bergmann 2021), force calibration and vibroacoustic monitoring. Every function takes
a Job (or a Path) and returns the CLI's JSON document as a dict with its series as numpy
arrays. Units as at the CLI: mm, s, mm/min, rpm, degrees, N; each key and array carries its
unit in its name (x_mm, t_s, f_x_n, engagement_deg).

    import trochomill as tm
    job = tm.Job.from_toml("examples/wagih2023/elliptical.toml")
    job.set("path.aspect_ratio", 0.8)
    result = tm.analyze(job)
    result["h_max_mm"], result["series"]["h_max_mm"]

Bad input raises trochomill.InputError (a ValueError) with the message the CLI gives; a
file that cannot be read OSError; Ctrl-C during a long call KeyboardInterrupt.
"""

from ._trochomill import (
    Error,
    InputError,
    Job,
    Path,
    __version__,
    analyze,
    calibrate,
    compare,
    forces,
    keys,
    materials,
    mechanism,
    monitor,
    plan,
    read_drawing,
    read_gcode,
    recommend,
    report,
    optimize_feed,
    schedule_feed,
    simulate,
    spectrum,
    synth_signal,
    texture_areal,
    texture_profile,
)

__all__ = [
    "Error",
    "InputError",
    "Job",
    "Path",
    "__version__",
    "analyze",
    "calibrate",
    "compare",
    "forces",
    "keys",
    "materials",
    "mechanism",
    "monitor",
    "plan",
    "read_drawing",
    "read_gcode",
    "recommend",
    "report",
    "optimize_feed",
    "schedule_feed",
    "simulate",
    "spectrum",
    "synth_signal",
    "texture_areal",
    "texture_profile",
]

# Errors and objects name the package, not its extension module, in tracebacks and help().
for _name in __all__:
    _obj = globals()[_name]
    if getattr(_obj, "__module__", None) == "trochomill._trochomill":
        try:
            _obj.__module__ = "trochomill"
        except (AttributeError, TypeError):
            pass
del _name, _obj
