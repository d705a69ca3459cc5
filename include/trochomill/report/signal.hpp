// The monitor's results, live windows and spectra. Part of the report module (trochomill/report.hpp
// includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/signal.hpp"

namespace trochomill {

/// The monitor's results as JSON: keys `k_f_mean`, `k_f_per_cycle` (array), `cycles` (count),
/// `cycle_source`, `period_s`, `reference_k_f`, `wear_trend`, `flags` (strings), per-cycle
/// details under `cycle_details`, the settings, and the model profile (`model`) with a job.
[[nodiscard]] std::string monitor_json(const MonitorReport& r, const std::string& signal,
                                       const Signal& s, const MonitorSettings& m);
/// Per window: t_s, rms_low, rms_high, k_f, cycle (-1 outside), phase, zone (-1 unknown).
[[nodiscard]] std::string monitor_csv(const MonitorReport& r);
/// A short human summary.
[[nodiscard]] std::string monitor_table(const MonitorReport& r, const std::string& signal,
                                        const Signal& s);
/// One live window as a JSON line (newline-terminated).
[[nodiscard]] std::string live_json_line(const LiveWindow& w);
/// Welch PSD as CSV (f_hz, psd_per_hz) and a spectrogram in long form (t_s, f_hz, db).
[[nodiscard]] std::string spectrum_csv(const Spectrum& sp);
[[nodiscard]] std::string spectrogram_csv(const Spectrogram& sg);
/// `spectrum`'s summary: the rate, the bins and the eight strongest peaks.
[[nodiscard]] std::string spectrum_text(const std::string& file, const Signal& sig,
                                        const Spectrum& sp, int nfft);

}  // namespace trochomill
