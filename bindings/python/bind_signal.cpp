// monitor, spectrum and synth_signal: Pivkin 2025's vibroacoustic k_f monitor, the spectrum
// of a signal (to choose the monitor's bands), and a synthetic recording that follows the
// model's zones. Three registration functions: the module registers them at their places
// among the others (module.cpp).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "common.hpp"
#include "trochomill/report/signal.hpp"
#include "trochomill/signal.hpp"

namespace trochomill::python {

void bind_monitor(py::module_& m) {
  m.def(
      "monitor",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& samples,
         double rate_hz, const py::object& job_obj, double start_s, const py::object& set) {
        if (!(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 1e7)) {
          throw InputError(fmt::format("rate_hz must be in (0, 1e7] Hz, got {}", rate_hz));
        }
        if (!(std::isfinite(start_s) && start_s >= 0 && start_s <= 1e9)) {
          throw InputError(fmt::format("start_s must be in [0, 1e9] s, got {}", start_s));
        }
        const std::vector<Override> keys = overrides_of(set);
        std::optional<Job> job;
        MonitorSettings ms;
        if (!job_obj.is_none()) {
          const PyJob& pj = job_obj.cast<const PyJob&>();
          job = keys.empty() ? pj.job : pj.with(keys);
          ms = job->monitor;
        } else {
          ms = monitor_settings_without_job(keys);
        }
        Signal sig;
        sig.rate_hz = rate_hz;
        sig.samples = finite_vector(samples, "samples");
        MonitorReport r = run_released([&](const RunHooks&) {
          return analyze_signal(sig, ms, job ? &*job : nullptr, start_s);
        });
        py::dict out = from_json(monitor_json(r, "<array>", sig, ms));
        py::dict windows;
        windows["t_s"] = to_array(std::move(r.kf.t_s));
        windows["rms_low"] = to_array(std::move(r.kf.rms_low));
        windows["rms_high"] = to_array(std::move(r.kf.rms_high));
        windows["k_f"] = to_array(std::move(r.kf.k_f));
        out["windows"] = windows;
        return out;
      },
      py::arg("samples"), py::arg("rate_hz"), py::kw_only(), py::arg("job") = py::none(),
      py::arg("start_s") = 0.0, py::arg("set") = py::none(),
      R"(The vibroacoustic monitor (Pivkin 2025): k_f = RMS(low band) / RMS(high band) per
window and per trochoid cycle, with flags. samples: one channel (float64, any unit) at
rate_hz (Hz); job: the cycle timing and the model's zones (without one the cycles come from
the signal's period); start_s: where the program starts in the recording (s); set:
{"monitor.key": value} overrides (bands low_min/low_max/high_min/high_max in Hz, order,
window in s). Returns the keys of `trochomill monitor --json`, "windows" (t_s, rms_low,
rms_high, k_f arrays).)");
}

void bind_spectrum(py::module_& m) {
  m.def(
      "spectrum",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& samples,
         double rate_hz, int nfft, bool with_spectrogram) {
        if (!(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 1e7)) {
          throw InputError(fmt::format("rate_hz must be in (0, 1e7] Hz, got {}", rate_hz));
        }
        if (nfft < 16 || nfft > (1 << 24)) {
          throw InputError(fmt::format("nfft must be in [16, 16777216], got {}", nfft));
        }
        Signal sig;
        sig.rate_hz = rate_hz;
        sig.samples = finite_vector(samples, "samples");
        Spectrum sp = run_released([&](const RunHooks&) { return welch(sig, nfft); });
        py::dict out;
        out["f_hz"] = to_array(std::move(sp.f_hz));
        out["psd_per_hz"] = to_array(std::move(sp.psd));
        if (with_spectrogram) {
          Spectrogram sg = run_released([&](const RunHooks&) { return spectrogram(sig, nfft); });
          const auto frames = static_cast<py::ssize_t>(sg.db.size());
          const auto bins = static_cast<py::ssize_t>(sg.f_hz.size());
          std::vector<double> db;
          db.reserve(static_cast<std::size_t>(frames * bins));
          for (const auto& row : sg.db) db.insert(db.end(), row.begin(), row.end());
          py::dict g;
          g["t_s"] = to_array(std::move(sg.t_s));
          g["f_hz"] = to_array(std::move(sg.f_hz));
          g["db"] = to_array(std::move(db), {frames, bins});
          out["spectrogram"] = g;
        }
        return out;
      },
      py::arg("samples"), py::arg("rate_hz"), py::kw_only(), py::arg("nfft") = 4096,
      py::arg("spectrogram") = false,
      R"(Welch power spectral density of one channel, as `trochomill spectrum` (to choose the
monitor's bands): samples (float64, any unit U) at rate_hz (Hz), nfft a power of two
(Hann windows, half overlap). Returns f_hz and psd_per_hz (U^2/Hz) arrays; with
spectrogram=True also "spectrogram": t_s (frame centres), f_hz and db (frames, bins:
20 log10 of the amplitude).)");
}

void bind_synth_signal(py::module_& m) {
  m.def(
      "synth_signal",
      [](const PyJob& pj, double rate_hz, int cycles, double kf_czi, double kf_czii,
         double kf_cziii, std::optional<double> kf_czii_down, std::optional<double> kf_cziii_down,
         double wear_drift, double noise, double lead_s, std::uint32_t seed,
         std::optional<double> memory_limit_gb) {
        struct Range {
          const char* name;
          double v, lo, hi;
          bool open_lo;
        };
        for (const Range& r :
             {Range{"rate_hz", rate_hz, 0, 1e7, true},
              Range{"cycles", static_cast<double>(cycles), 1, 100000, false},
              Range{"kf_czi", kf_czi, 0, 100, true}, Range{"kf_czii", kf_czii, 0, 100, true},
              Range{"kf_cziii", kf_cziii, 0, 100, true},
              Range{"kf_czii_down", kf_czii_down.value_or(1), 0, 100, true},
              Range{"kf_cziii_down", kf_cziii_down.value_or(1), 0, 100, true},
              Range{"wear_drift", wear_drift, 0, 100, false}, Range{"noise", noise, 0, 100, false},
              Range{"lead_s", lead_s, 0, 1e4, false}}) {
          if (!(std::isfinite(r.v) && (r.open_lo ? r.v > r.lo : r.v >= r.lo) && r.v <= r.hi)) {
            throw InputError(fmt::format("{} must be in {}{}, {}], got {}", r.name,
                                         r.open_lo ? "(" : "[", r.lo, r.hi, r.v));
          }
        }
        SynthOptions o;
        o.rate_hz = rate_hz;
        o.cycles = cycles;
        o.kf_czi = kf_czi;
        o.kf_czii = kf_czii;
        o.kf_cziii = kf_cziii;
        o.kf_czii_down = kf_czii_down;
        o.kf_cziii_down = kf_cziii_down;
        o.wear_drift = wear_drift;
        o.noise = noise;
        o.lead_s = lead_s;
        o.seed = seed;
        check_memory(
            "synth_signal", synth_signal_memory_bytes(pj.job, o), memory_limit_gb,
            fmt::format("lower rate_hz (now {:g} Hz) or cycles (now {})", rate_hz, cycles));
        int covered = 0;
        Signal sig = run_released(
            [&](const RunHooks&) { return synth_signal(pj.job, pj.job.monitor, o, &covered); });
        py::dict out;
        out["rate_hz"] = sig.rate_hz;
        out["cycles"] = covered;
        out["start_s"] = lead_s;
        out["samples"] = to_array(std::move(sig.samples));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("rate_hz") = 100000.0, py::arg("cycles") = 12,
      py::arg("kf_czi") = 1.6, py::arg("kf_czii") = 1.0, py::arg("kf_cziii") = 1.0,
      py::arg("kf_czii_down") = py::none(), py::arg("kf_cziii_down") = py::none(),
      py::arg("wear_drift") = 0.0, py::arg("noise") = 0.02, py::arg("lead_s") = 0.1,
      py::arg("seed") = 1, py::arg("memory_limit_gb") = py::none(),
      R"(A synthetic vibroacoustic signal following the model's zones, as `trochomill
synth-signal` writes it: per cycle of the steady trochoid, noise bands whose RMS ratio is
k_f of the zone (kf_czi, kf_czii, kf_cziii; kf_czii_down and kf_cziii_down, when given, in
the cut's second, down-cut half), a wear drift (k_f x (1 + wear_drift) by the last
cycle), white noise (RMS relative to cutting), lead_s (s) of air before the program.
Returns {"samples": float64 array, "rate_hz", "cycles" (covered), "start_s"}.)");
}

}  // namespace trochomill::python
