# Typing stub of the trochomill module (the extension's functions and classes). Units: mm, s,
# mm/min, rpm, degrees, N; every key and array names its unit.
import os
from typing import Any, Callable, Mapping, Sequence

import numpy as np
import numpy.typing as npt

__version__: str

_F64 = npt.NDArray[np.float64]
_Progress = Callable[[str, int, int], object] | None
_Value = bool | int | float | str | Sequence[Any]

class Error(RuntimeError): ...

class InputError(ValueError):
    """Bad input: the message names the key or file:line:column and what is allowed."""

    problems: list[str]

class Job:
    """A job: tool, slot, path, cutting conditions, machine, material and settings."""

    @staticmethod
    def from_toml(path: str | os.PathLike[str], set: Mapping[str, _Value] | None = None) -> Job: ...
    @staticmethod
    def from_text(text: str, name: str = "<text>", set: Mapping[str, _Value] | None = None) -> Job: ...
    @staticmethod
    def from_dict(sections: Mapping[str, Mapping[str, _Value]], name: str = "<dict>") -> Job: ...
    def set(self, key: str, value: _Value) -> None:
        """Sets "section.key" (as --set); the job stays as it was when the value is refused."""
    def copy(self) -> Job: ...
    def to_dict(self) -> dict[str, dict[str, Any]]: ...
    def to_toml(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def feed_rate_mm_per_min(self) -> float: ...
    @property
    def spindle_speed_rpm(self) -> float: ...
    @property
    def tooth_period_s(self) -> float: ...

class Path:
    """A tool-centre path (mm, s): planned, or read from an NC program."""

    @property
    def length_mm(self) -> float: ...
    @property
    def feed_length_mm(self) -> float: ...
    @property
    def duration_s(self) -> float: ...
    def time_s(self) -> float:
        """Time with the job's acceleration limit (s)."""
    @property
    def segments(self) -> int: ...
    @property
    def cycles(self) -> int: ...
    @property
    def cycle_start_s(self) -> _F64: ...
    @property
    def extra_axes(self) -> dict[str, dict[str, float]]:
        """The axes besides X Y Z a program moves: {'A': {'min_deg': .., 'max_deg': ..}, ..}."""
    @property
    def extra_axes_only_time_s(self) -> float: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def pocket(self) -> dict[str, Any] | None:
        """A planned pocket's figures and the kernel's proof (`plan --json`); None otherwise."""
    @property
    def source(self) -> str: ...
    @property
    def job(self) -> Job | None: ...
    def sample(self, dt_s: float | None = None, ds_mm: float | None = None) -> dict[str, npt.NDArray[Any]]:
        """Arrays t_s, s_mm, x_mm, y_mm, z_mm, feed_mm_per_min (float64) and rapid (bool)."""
    def gcode(self, dialect: str | None = None) -> str:
        """The program text: linuxcnc, fanuc, sinumerik, grbl, haas or mach3 (default the job's)."""

def plan(job: Job, memory_limit_gb: float | None = None) -> Path: ...
def read_gcode(program: str | os.PathLike[str], job: Job | None = None) -> Path: ...
def analyze(job: Job | Path, *, memory_limit_gb: float | None = None,
            progress: _Progress = None, walls: bool = True, floor: bool = True,
            force: bool = True) -> dict[str, Any]:
    """`analyze --json`'s keys and "series" (t_s, x_mm, y_mm, z_mm, engagement_deg,
    h_max_mm, mrr_mm3_per_min, radial_engagement_mm, teeth_in_cut); walls, floor, force:
    the parts computed (a part left out gives None for its keys)."""
def compare(job: Job, vary: Mapping[str, Sequence[_Value]], *, threads: int = 0,
            progress: _Progress = None) -> dict[str, Any]:
    """Columns: each varied key, "ok", "error" and each number of analyze's JSON."""
def mechanism(job: Job, *, model: str | None = None,
              flank_wear_mm: float | None = None) -> dict[str, Any]:
    """`mechanism --json`'s keys; curves theta_deg, t_s, h_mm, psi_deg, teeth_in_contact,
    gamma_k_deg, kappa_deg, k_re_pct, zone as arrays."""
def recommend(job: Job, *, share: float | None = None, share_of: str | None = None,
              feed: bool = False) -> dict[str, Any]: ...
def simulate(job: Job | Path, *, cycles: tuple[int, int] | None = None, from_s: float | None = None,
             to_s: float | None = None, progress: _Progress = None,
             memory_limit_gb: float | None = None) -> dict[str, Any]:
    """`simulate --json`'s keys, "series", "chip_map" and "surface" (vertices_mm, faces)."""
def forces(job: Job | Path, *, fast: bool = True, cycles: tuple[int, int] | None = None,
           from_s: float | None = None, to_s: float | None = None, progress: _Progress = None,
           memory_limit_gb: float | None = None) -> dict[str, Any]:
    """`forces --json`'s keys and "series" (t_s, f_x_n, f_y_n, f_z_n, f_resultant_n,
    torque_nm, power_w, tooth_* (steps, teeth))."""
def calibrate(job: Job | Path, t_s: npt.ArrayLike, f_n: npt.ArrayLike, *, fit: Sequence[str] = ...,
              model: str | None = None, fast: bool = False, cutoff_hz: float | None = None,
              max_shift_s: float | None = None, cycles: tuple[int, int] | None = None,
              from_s: float | None = None, to_s: float | None = None, progress: _Progress = None,
              memory_limit_gb: float | None = None) -> dict[str, Any]:
    """`calibrate --json`'s keys and "material_toml"."""
def report(job: Job | Path, output: str | os.PathLike[str] | None = None, *,
           parts: Sequence[str] = ..., cycles: tuple[int, int] | None = None,
           from_s: float | None = None, to_s: float | None = None,
           signal: npt.ArrayLike | None = None, rate_hz: float | None = None,
           start_s: float | None = None, measured_t_s: npt.ArrayLike | None = None,
           measured_f_n: npt.ArrayLike | None = None,
           vary: Mapping[str, Sequence[_Value]] | None = None, progress: _Progress = None,
           memory_limit_gb: float | None = None) -> str:
    """`trochomill report`'s self-contained HTML page (also written to `output`)."""
def monitor(samples: npt.ArrayLike, rate_hz: float, *, job: Job | None = None, start_s: float = 0.0,
            set: Mapping[str, _Value] | None = None) -> dict[str, Any]:
    """`monitor --json`'s keys and "windows" (t_s, rms_low, rms_high, k_f)."""
def synth_signal(job: Job, *, rate_hz: float = 100000.0, cycles: int = 12, kf_czi: float = 1.6,
                 kf_czii: float = 1.15, kf_cziii: float = 1.0, wear_drift: float = 0.0,
                 noise: float = 0.02, lead_s: float = 0.1, seed: int = 1,
                 memory_limit_gb: float | None = None) -> dict[str, Any]:
    """{"samples": float64 array, "rate_hz", "cycles", "start_s"}."""
def texture_profile(z_mm: npt.ArrayLike, dx_mm: float, *, lambda_c_mm: float | None = None,
                    lambda_s_mm: float | None = None, robust: bool = False) -> dict[str, Any]:
    """The CLI texture JSON's keys and "profile" (x_mm, roughness_mm, waviness_mm)."""
def texture_areal(z_mm: npt.ArrayLike, dx_mm: float, dy_mm: float, *, s_mm: float | None = None,
                  l_mm: float | None = None, form: str = "plane", degree: int = 2,
                  memory_limit_gb: float | None = None) -> dict[str, Any]:
    """The CLI texture JSON's keys of an areal surface (S-F and S-L parameters)."""
def spectrum(samples: npt.ArrayLike, rate_hz: float, *, nfft: int = 4096,
             spectrogram: bool = False) -> dict[str, Any]:
    """f_hz and psd_per_hz arrays (and "spectrogram": t_s, f_hz, db)."""
def read_drawing(file: str, *, layers: list[str] | None = None,
                 join_tolerance_mm: float = 0.01,
                 arc_tolerance_mm: float = 0.002) -> dict[str, Any]:
    """A DXF or SVG drawing as `check-drawing --json` reports it: unit, layers, contours."""
def keys() -> list[dict[str, str]]:
    """Every job key: section, key, type, unit, allowed, default, doc."""
def materials() -> list[dict[str, Any]]:
    """The materials library."""
def schedule_feed(job: Job | Path, *, h_max_mm: float | None = None,
                  mrr_mm3_per_min: float | None = None,
                  min_feed_mm_per_min: float | None = None,
                  max_feed_mm_per_min: float | None = None, air_feed_mm_per_min: float | None = None,
                  feed_step_percent: float = 5.0, piece_mm: float = 0.5,
                  progress: _Progress = None,
                  h_axial_max_mm: float | None = None) -> dict[str, Any]:
    """"path" (the scheduled Path), times and chips before and after, per-piece arrays."""
def optimize_feed(program: str, job: Job, *, h_max_mm: float | None = None,
                  mrr_mm3_per_min: float | None = None, force_n: float | None = None,
                  power_w: float | None = None, torque_nm: float | None = None,
                  min_feed_mm_per_min: float | None = None,
                  max_feed_mm_per_min: float | None = None, air_feed_mm_per_min: float | None = None,
                  feed_step_percent: float = 5.0, piece_mm: float = 0.5,
                  include_dirs: list[str] = ..., engine: str = "kernel",
                  stock: str | None = None, rounds: int | None = None,
                  progress: _Progress = None, memory_limit_gb: float | None = None,
                  h_axial_max_mm: float | None = None) -> dict[str, Any]:
    """The optimize-feed summary, "text" (the rewritten program), "before"/"after" series."""
