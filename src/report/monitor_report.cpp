// Formatting of the vibroacoustic monitor's results (include/trochomill/report.hpp).
#include <fmt/format.h>

#include <cmath>
#include <iterator>
#include <nlohmann/json.hpp>

#include "trochomill/report/signal.hpp"

namespace trochomill {

namespace {

nlohmann::json num(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}
nlohmann::json opt(const std::optional<double>& v) { return v ? num(*v) : nlohmann::json(nullptr); }

// Cycle, phase and zone of window i (the cycles are sorted and disjoint).
struct Where {
  int cycle = -1;
  double phase = -1;
  int zone = -1;
};
Where where(const MonitorReport& r, double t) {
  Where w;
  for (std::size_t k = 0; k < r.cycles.size(); ++k) {
    const auto& c = r.cycles[k];
    if (t >= c.start_s && t < c.end_s) {
      w.cycle = static_cast<int>(k);
      w.phase = (t - c.start_s) / (c.end_s - c.start_s);
      if (r.model) {
        const auto bins = r.model->zone.size();
        w.zone = r.model->zone[std::min(
            bins - 1, static_cast<std::size_t>(w.phase * static_cast<double>(bins)))];
      }
      break;
    }
  }
  return w;
}

}  // namespace

std::string monitor_json(const MonitorReport& r, const std::string& signal, const Signal& s,
                         const MonitorSettings& m) {
  nlohmann::json j;
  j["signal"] = signal;
  j["rate_hz"] = s.rate_hz;
  j["duration_s"] = s.duration_s();
  j["bands_hz"] = {{"low", {m.low_min_hz, m.low_max_hz}}, {"high", {m.high_min_hz, m.high_max_hz}}};
  j["order"] = m.order;
  j["window_s"] = r.kf.window_s;
  j["k_f_mean"] = num(r.k_f_mean);
  j["cycles"] = r.cycles.size();
  j["cycle_source"] = r.timing.source;
  j["period_s"] = r.timing.period_s;
  j["reference_k_f"] = num(r.reference_k_f);
  j["wear_trend"] = r.wear_trend;
  j["criteria"] = r.model ? std::string(to_string(m.criteria)) : std::string("none");
  j["cycles_by_tool_state"] = {
      {"new", r.cycles_new}, {"worn", r.cycles_worn}, {"neither", r.cycles_neither}};
  j["flags"] = r.flags;
  j["warnings"] = r.warnings;
  j["k_f_per_cycle"] = nlohmann::json::array();
  j["cycle_details"] = nlohmann::json::array();
  for (const auto& c : r.cycles) {
    j["k_f_per_cycle"].push_back(num(c.k_f_mean));
    nlohmann::json profile = nlohmann::json::array();
    for (const double v : c.k_f_profile) profile.push_back(num(v));
    nlohmann::json judged = nlohmann::json::array();
    for (const auto& q : c.judged) {
      judged.push_back({{"zone", q.zone == 2 ? "CZII" : "CZIII"},
                        {"half", q.half == 1 ? "up-cut" : "down-cut"},
                        {"k_f", num(q.k_f)},
                        {"windows", q.windows},
                        {"new_range", {q.new_range.lo, q.new_range.hi}},
                        {"worn_range", {q.worn_range.lo, q.worn_range.hi}},
                        {"in_new", q.in_new},
                        {"in_worn", q.in_worn}});
    }
    j["cycle_details"].push_back(
        {{"start_s", c.start_s},
         {"end_s", c.end_s},
         {"k_f_mean", num(c.k_f_mean)},
         {"k_f_czi", opt(c.k_f_czi)},
         {"k_f_cziii", opt(c.k_f_cziii)},
         {"ploughing", c.ploughing},
         {"wear", c.wear},
         {"tool_state",
          c.tool_state.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.tool_state)},
         {"judged", judged},
         {"k_f_profile", profile}});
  }
  if (r.model) {
    nlohmann::json phase = nlohmann::json::array();
    const auto bins = r.model->zone.size();
    for (std::size_t b = 0; b < bins; ++b)
      phase.push_back((static_cast<double>(b) + 0.5) / static_cast<double>(bins));
    j["model"] = {{"phase", phase}, {"k_re_pct", r.model->k_re_pct}, {"zone", r.model->zone}};
  }
  return j.dump(2) + "\n";
}

std::string monitor_csv(const MonitorReport& r) {
  std::string out = "t_s,rms_low,rms_high,k_f,cycle,phase,zone\n";
  for (std::size_t i = 0; i < r.kf.t_s.size(); ++i) {
    const Where w = where(r, r.kf.t_s[i]);
    fmt::format_to(std::back_inserter(out), "{:.6f},{:.6g},{:.6g},{:.6g},{},{:.5f},{}\n",
                   r.kf.t_s[i], r.kf.rms_low[i], r.kf.rms_high[i], r.kf.k_f[i], w.cycle, w.phase,
                   w.zone);
  }
  return out;
}

std::string monitor_table(const MonitorReport& r, const std::string& signal, const Signal& s) {
  std::string out = fmt::format(
      "{}: {:.3f} s at {:g} Hz, {} windows of {:g} s; {} cycles ({}, period {:.4f} s)\n", signal,
      s.duration_s(), s.rate_hz, r.kf.t_s.size(), r.kf.window_s, r.cycles.size(), r.timing.source,
      r.timing.period_s);
  fmt::format_to(std::back_inserter(out), "  k_f mean {:.3f}, reference (first cycles) {:.3f}\n",
                 r.k_f_mean, r.reference_k_f);
  for (std::size_t k = 0; k < r.cycles.size(); ++k) {
    const auto& c = r.cycles[k];
    fmt::format_to(std::back_inserter(out), "  cycle {:3} {:9.4f} s  k_f {:.3f}", k, c.start_s,
                   c.k_f_mean);
    if (c.k_f_czi && c.k_f_cziii) {
      fmt::format_to(std::back_inserter(out), "  CZI {:.3f} CZIII {:.3f}", *c.k_f_czi,
                     *c.k_f_cziii);
    }
    if (c.ploughing) out += "  ploughing?";
    if (c.wear) out += "  wear";
    if (!c.tool_state.empty()) out += "  ranges: " + c.tool_state;
    out += "\n";
  }
  if (r.flags.empty()) out += "  no flags\n";
  for (const auto& f : r.flags) out += "  flag: " + f + "\n";
  return out;
}

std::string live_json_line(const LiveWindow& w) {
  nlohmann::json j = {{"t_s", w.window.t_s},
                      {"rms_low", num(w.window.rms_low)},
                      {"rms_high", num(w.window.rms_high)},
                      {"k_f", num(w.window.k_f)},
                      {"cycle", w.cycle},
                      {"phase", w.phase >= 0 ? num(w.phase) : nlohmann::json(nullptr)},
                      {"zone", w.zone},
                      {"half", w.half},
                      {"flags", w.flags}};
  return j.dump() + "\n";
}

std::string spectrum_csv(const Spectrum& sp) {
  std::string out = "f_hz,psd_per_hz\n";
  for (std::size_t k = 0; k < sp.f_hz.size(); ++k) {
    fmt::format_to(std::back_inserter(out), "{:.4f},{:.6g}\n", sp.f_hz[k], sp.psd[k]);
  }
  return out;
}

std::string spectrogram_csv(const Spectrogram& sg) {
  std::string out = "t_s,f_hz,db\n";
  for (std::size_t i = 0; i < sg.t_s.size(); ++i) {
    for (std::size_t k = 0; k < sg.f_hz.size(); ++k) {
      fmt::format_to(std::back_inserter(out), "{:.6f},{:.4f},{:.2f}\n", sg.t_s[i], sg.f_hz[k],
                     sg.db[i][k]);
    }
  }
  return out;
}

}  // namespace trochomill

namespace trochomill {

std::string spectrum_text(const std::string& file, const Signal& sig, const Spectrum& sp,
                          int nfft) {
  std::string out = fmt::format("{}: {:.3f} s at {:g} Hz, Welch nfft {} ({:.2f} Hz bins)\n", file,
                                sig.duration_s(), sig.rate_hz, nfft, sig.rate_hz / nfft);
  for (const std::size_t k : spectrum_peaks(sp, 8)) {
    out += fmt::format("  peak {:10.1f} Hz  {:.3e} /Hz\n", sp.f_hz[k], sp.psd[k]);
  }
  return out;
}

}  // namespace trochomill
