// Vibroacoustic monitoring: filters against scipy.signal (frozen reference values,
// scripts/make-filter-reference), k_f of tones and noise, streaming against offline, cycle
// segmentation and wear flags on synthetic signals, readers.
#include "trochomill/signal.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

nlohmann::json reference() {
  std::ifstream in(std::string(TROCHOMILL_SOURCE_DIR) + "/tests/data/signal/scipy_reference.json");
  return nlohmann::json::parse(in);
}

Signal tones(double rate, double seconds, const std::vector<std::pair<double, double>>& fa) {
  Signal s;
  s.rate_hz = rate;
  const auto n = static_cast<std::size_t>(seconds * rate);
  s.samples.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    double v = 0;
    for (const auto& [f, a] : fa) v += a * std::sin(kTwoPi * f * static_cast<double>(i) / rate);
    s.samples[i] = v;
  }
  return s;
}

// The magnitude response of every design against scipy.signal.sosfreqz of scipy's own
// butter(..., output='sos'): the section pairing differs, the transfer function must not.
// Tolerance 1e-9 relative plus 1e-12 absolute (double rounding through up to 12 sections;
// the stopband values go down to ~1e-10). The band edges are -3 dB by construction.
TEST(Signal, ButterworthMatchesScipy) {
  const auto ref = reference();
  int checked = 0;
  for (const auto& d : ref["designs"]) {
    const Sos sos = butter_bandpass(d["order"], d["lo_hz"], d["hi_hz"], d["rate_hz"]);
    ASSERT_EQ(sos.sections.size(), d["order"].get<std::size_t>());
    for (std::size_t k = 0; k < d["f_hz"].size(); ++k) {
      const double want = d["gain"][k], got = sos_gain(sos, d["f_hz"][k], d["rate_hz"]);
      EXPECT_NEAR(got, want, 1e-9 * want + 1e-12) << d.dump() << " f " << d["f_hz"][k];
      ++checked;
    }
    EXPECT_NEAR(sos_gain(sos, d["lo_hz"], d["rate_hz"]), 1 / std::sqrt(2.0), 1e-12);
    EXPECT_NEAR(sos_gain(sos, d["hi_hz"], d["rate_hz"]), 1 / std::sqrt(2.0), 1e-12);
  }
  EXPECT_EQ(checked, 12 * 11);
}

// Filter outputs sample by sample against scipy's sosfilt and sosfiltfilt (odd padding,
// steady-state initial conditions) on a two-tone input with a step: within 1e-10 (outputs
// are O(1); the realisations differ in section pairing, so only rounding may differ).
TEST(Signal, FilteringMatchesScipy) {
  const auto f = reference()["filter"];
  const Sos sos = butter_bandpass(f["order"], f["lo_hz"], f["hi_hz"], f["rate_hz"]);
  std::vector<double> x(2000);
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double r = f["rate_hz"], t = static_cast<double>(i);
    x[i] = std::sin(kTwoPi * 3000.0 * t / r) + 0.5 * std::sin(kTwoPi * 11000.0 * t / r) +
           (i >= 700 ? 0.3 : 0.0);
  }
  const std::vector<double> y = sosfilt(sos, x), yy = sosfiltfilt(sos, x);
  // The two-band versions (both lanes of a vector register) equal the single ones exactly.
  const Sos other = butter_bandpass(4, 8000, 13000, f["rate_hz"]);
  std::vector<double> pa, pb, qa, qb;
  sosfilt_pair(sos, other, x, pa, pb);
  sosfiltfilt_pair(sos, other, x, qa, qb);
  EXPECT_EQ(pa, y);
  EXPECT_EQ(pb, sosfilt(other, x));
  EXPECT_EQ(qa, yy);
  EXPECT_EQ(qb, sosfiltfilt(other, x));
  // Three signals through one filter side by side (a force's x, y, z): each exactly its own.
  std::vector<double> x2(x.size()), x3(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    x2[i] = -2.0 * x[i] + 0.1;
    x3[i] = x[(i * 7) % x.size()];
  }
  std::array<std::vector<double>, 3> xyz{x, x2, x3};
  sosfiltfilt_three(sos, xyz);
  EXPECT_EQ(xyz[0], yy);
  EXPECT_EQ(xyz[1], sosfiltfilt(sos, x2));
  EXPECT_EQ(xyz[2], sosfiltfilt(sos, x3));
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_NEAR(y[i], f["sosfilt"][i].get<double>(), 1e-10) << i;
    EXPECT_NEAR(yy[i], f["sosfiltfilt"][i].get<double>(), 1e-10) << i;
  }
}

// Zero phase: a tone at a band edge comes out at half its amplitude (|H|^2 = 1/2) and in
// phase; at the centre whole. Checked on the middle second of two (away from the ends'
// transients): within 1e-3 of the amplitude.
TEST(Signal, ZeroPhaseGainAndPhase) {
  const double rate = 100000;
  const Sos sos = butter_bandpass(4, 2000, 5000, rate);
  for (const auto& [f, gain] : {std::pair{2000.0, 0.5}, std::pair{5000.0, 0.5},
                                std::pair{std::sqrt(2000.0 * 5000.0), 1.0}}) {
    const Signal s = tones(rate, 2.0, {{f, 1.0}});
    const std::vector<double> y = sosfiltfilt(sos, s.samples);
    double worst = 0;
    for (std::size_t i = 50000; i < 150000; ++i) {
      worst = std::max(worst, std::abs(y[i] - gain * s.samples[i]));
    }
    EXPECT_LT(worst, 1e-3) << f;
  }
}

// Two tones at the band centres with amplitude ratio A: every window's k_f = A within 0.5 %
// (windows of 20 ms hold 63 periods of the lower tone, so a partial period moves the mean
// square by < 1 / (4 pi 63) = 0.13 %; the other band's leakage is below -100 dB zero-phase).
TEST(Signal, TwoTonesGiveTheirAmplitudeRatio) {
  MonitorSettings m;
  m.window_s = 0.02;
  const double fl = std::sqrt(m.low_min_hz * m.low_max_hz),
               fh = std::sqrt(m.high_min_hz * m.high_max_hz);
  for (const double A : {0.5, 1.0, 3.0}) {
    const Signal s = tones(100000, 1.0, {{fl, A}, {fh, 1.0}});
    const KfSeries k = kf_series(s, m, true);
    ASSERT_EQ(k.k_f.size(), 50u);
    for (std::size_t i = 2; i + 2 < k.k_f.size(); ++i) EXPECT_NEAR(k.k_f[i], A, 0.005 * A) << i;
  }
}

// White noise: RMS_low / RMS_high = sqrt(3000 / 5000) within 2 % (the bands' shapes are the
// same Butterworth scaled by their widths; the bilinear warping stretches the high band by
// ~1 % more, and 10 s of noise in a 3 kHz band estimate the ratio to ~0.3 %).
TEST(Signal, WhiteNoiseGivesTheBandwidthRatio) {
  Signal s;
  s.rate_hz = 100000;
  s.samples.resize(1000000);
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  for (double& v : s.samples) v = g(rng);
  MonitorSettings m;
  m.window_s = 0.1;
  const KfSeries k = kf_series(s, m, true);
  double sl = 0, sh = 0;
  for (std::size_t i = 0; i < k.k_f.size(); ++i) {
    sl += k.rms_low[i] * k.rms_low[i];
    sh += k.rms_high[i] * k.rms_high[i];
  }
  EXPECT_NEAR(std::sqrt(sl / sh), std::sqrt(3000.0 / 5000.0), 0.02 * std::sqrt(0.6));
}

// Streaming (causal, pushed in uneven pieces, some longer than its 4096-sample blocks) equals
// the offline causal series exactly.
TEST(Signal, StreamingEqualsOfflineCausal) {
  Signal s;
  s.rate_hz = 48000;
  s.samples.resize(48000);
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  for (double& v : s.samples) v = g(rng);
  MonitorSettings m;
  const KfSeries off = kf_series(s, m, false);
  KfStream stream(s.rate_hz, m);
  std::vector<KfStream::Window> got;
  std::size_t pos = 0, piece = 1;
  while (pos < s.samples.size()) {
    const std::size_t n = std::min(piece, s.samples.size() - pos);
    stream.push(s.samples.data() + pos, n, [&](const KfStream::Window& w) { got.push_back(w); });
    pos += n;
    piece = piece * 3 % 9973 + 1;  // up to 9973: more than one of the stream's blocks
  }
  ASSERT_EQ(got.size(), off.k_f.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].rms_low, off.rms_low[i]);
    EXPECT_EQ(got[i].rms_high, off.rms_high[i]);
    EXPECT_EQ(got[i].k_f, off.k_f[i]);
    EXPECT_EQ(got[i].t_s, off.t_s[i]);
  }
}

// Pivkin's example with a blunter edge (r_e 30 um), so that every zone holds many windows.
Job pivkin_job() {
  return load_job(test::example("pivkin2025/trochoidal.toml"),
                  {parse_override("tool.edge_radius=0.03")});
}

// A synthetic recording of the Pivkin example: its cycles are found from the signal alone
// (period within 0.5 % of the planned cycle time, starts within two windows of the cut's
// onsets, which the model puts `cutting_start` into the cycle, i.e. just before theta = 0)
// and from the job (exactly the planned starts).
TEST(Signal, SegmentationRecoversSyntheticCycles) {
  const Job job = pivkin_job();
  SynthOptions o;
  o.cycles = 10;
  const Signal s = synth_signal(job, job.monitor, o);
  const PlannedPath pp = plan_path(job);
  std::vector<double> truth;
  for (const auto& mk : pp.path.cycles()) truth.push_back(o.lead_s + mk.start_time_s);
  const double T = truth[2] - truth[1];
  const MechanismSettings st = job.mechanism;
  const MechanismCurve curve = mechanism_curve(job, st);
  double onset = summarize_zones(curve, st, false).cutting_start_s;
  if (onset > 0.5 * curve.cycle_time_s) onset -= curve.cycle_time_s;
  const MonitorReport by_signal = analyze_signal(s, job.monitor, nullptr, 0);
  EXPECT_EQ(by_signal.timing.source, "signal");
  EXPECT_NEAR(by_signal.timing.period_s, T, 0.005 * T);
  ASSERT_GE(by_signal.cycles.size(), 8u);
  const double w = by_signal.kf.window_s;
  for (const double a : by_signal.timing.start_s) {
    // The nearest true onset (the first cycle's is its start: the synthetic entry is air).
    double best = 1e9;
    for (const double b : truth) {
      best = std::min({best, std::abs(a - (b + onset)), b == truth[0] ? std::abs(a - b) : 1e9});
    }
    EXPECT_LT(best, 2 * w) << a;
  }
  const MonitorReport by_job = analyze_signal(s, job.monitor, &job, o.lead_s);
  EXPECT_EQ(by_job.timing.source, "job");
  ASSERT_EQ(by_job.cycles.size(), 10u);
  for (std::size_t k = 0; k < 10; ++k) EXPECT_NEAR(by_job.cycles[k].start_s, truth[k], 1e-9);
  ASSERT_TRUE(by_job.model.has_value());
  EXPECT_EQ(by_job.model->zone.size(), static_cast<std::size_t>(job.monitor.phase_bins));
  // k_f in CZIII reads the synthetic 1.0 and in CZI 1.6, averaged over the cycles. A 5 ms
  // window of 3-5 kHz noise holds ~15 independent samples, so one window's k_f scatters by
  // ~18 %: CZIII's ~120 windows per cycle give the mean within 3 %; CZI's few windows per
  // cycle, some straddling CZII (1.15) or air, within 15 %.
  double czi = 0, cziii = 0;
  for (const auto& c : by_job.cycles) {
    ASSERT_TRUE(c.k_f_cziii.has_value());
    ASSERT_TRUE(c.k_f_czi.has_value());
    czi += *c.k_f_czi / 10;
    cziii += *c.k_f_cziii / 10;
  }
  EXPECT_NEAR(cziii, 1.0, 0.03);
  EXPECT_NEAR(czi, 1.6, 0.15 * 1.6);
}

// A slow wear drift (k_f doubling over the recording) is flagged; a stationary signal is
// not. Ploughing: CZI's k_f 1.6 against CZIII's 1.0 is flagged (ratio 1.15), 1.0 is not.
TEST(Signal, WearDriftAndPloughingFlags) {
  const Job job = pivkin_job();
  SynthOptions o;
  o.cycles = 10;
  o.wear_drift = 1.0;
  const MonitorReport worn =
      analyze_signal(synth_signal(job, job.monitor, o), job.monitor, &job, o.lead_s);
  EXPECT_TRUE(worn.wear_trend);
  EXPECT_FALSE(worn.flags.empty());
  EXPECT_TRUE(worn.cycles.back().wear);
  EXPECT_FALSE(worn.cycles.front().wear);
  o.wear_drift = 0;
  const MonitorReport steady =
      analyze_signal(synth_signal(job, job.monitor, o), job.monitor, &job, o.lead_s);
  EXPECT_FALSE(steady.wear_trend);
  for (const auto& c : steady.cycles) EXPECT_FALSE(c.wear);
  EXPECT_NEAR(steady.reference_k_f, steady.k_f_mean, 0.02 * steady.k_f_mean);
  int ploughing = 0;
  for (const auto& c : steady.cycles) ploughing += c.ploughing;
  EXPECT_EQ(ploughing, 10);
  o.kf_czi = 1.0;
  const MonitorReport clean =
      analyze_signal(synth_signal(job, job.monitor, o), job.monitor, &job, o.lead_s);
  for (const auto& c : clean.cycles) EXPECT_FALSE(c.ploughing);
}

// Pivkin 2025's k_f ranges, judged per zone and half of the cut: synthetic recordings of
// the paper's example (edge radius 0.03 mm, as the tests above) built inside the new tool's
// ranges (CZII and CZIII 1.0), inside the worn tool's (CZII 1.6; CZIII 1.9 in the up-cut
// half, 1.3 in the down-cut half), outside both (CZIII 3.0), and with only the down-cut half
// of CZIII out of the new range. CZIII fills most of both halves; CZII is brief where the
// cut starts (the chip grows fast) and longer where it ends, so its up-cut cell has too few
// windows to judge and its down-cut cell is judged. Each value sits at least 0.15 inside (or
// outside) every range edge it tests; a 5 ms window's k_f scatters by ~18 %, so the cells'
// means (checked: at least 8 windows in CZII's, 25 in CZIII's) lie within ~6 % and ~4 % of
// the synthetic values (one standard deviation; the recording's seed is fixed).
TEST(Signal, RangesJudgeEachZoneAndHalf) {
  const Job job = pivkin_job();
  const auto run = [&](double czii, double cziii, double czii_down, double cziii_down) {
    SynthOptions o;
    o.cycles = 6;
    o.kf_czii = czii;
    o.kf_cziii = cziii;
    o.kf_czii_down = czii_down;
    o.kf_cziii_down = cziii_down;
    return analyze_signal(synth_signal(job, job.monitor, o), job.monitor, &job, o.lead_s);
  };
  // Every cell judged, each on enough windows.
  const MonitorReport fresh = run(1.0, 1.0, 1.0, 1.0);
  ASSERT_EQ(fresh.cycles.size(), 6u);
  for (const auto& c : fresh.cycles) {
    ASSERT_EQ(c.judged.size(), 3u);
    for (const auto& j : c.judged) {
      EXPECT_FALSE(j.zone == 2 && j.half == 1);
      EXPECT_GE(j.windows, j.zone == 2 ? 8 : 25) << kf_cell_name(j.zone, j.half);
      EXPECT_NEAR(j.k_f, 1.0, j.zone == 2 ? 0.12 : 0.08) << kf_cell_name(j.zone, j.half);
    }
    EXPECT_EQ(c.tool_state, "new");
  }
  EXPECT_EQ(fresh.cycles_new, 6);
  for (const auto& f : fresh.flags) EXPECT_EQ(f.find("Pivkin"), std::string::npos) << f;

  const MonitorReport worn = run(1.6, 1.9, 1.6, 1.3);
  EXPECT_EQ(worn.cycles_worn, 6);
  for (const auto& c : worn.cycles) {
    for (const auto& j : c.judged) {
      EXPECT_FALSE(j.in_new) << kf_cell_name(j.zone, j.half);
      EXPECT_TRUE(j.in_worn) << kf_cell_name(j.zone, j.half);
    }
  }
  // A flag for each zone and half, naming the zone, the half and both ranges.
  const auto flag_with = [](const MonitorReport& r, const std::string& what) {
    return std::count_if(r.flags.begin(), r.flags.end(),
                         [&](const std::string& f) { return f.find(what) != std::string::npos; });
  };
  EXPECT_EQ(flag_with(worn, "CZIII up-cut half: k_f outside the new tool's 0.90-1.10"), 1);
  EXPECT_EQ(flag_with(worn, "inside the worn tool's 1.50-2.30 (Fig. 24) in 6 of them"), 1);
  EXPECT_EQ(flag_with(worn, "CZIII down-cut half"), 1);
  EXPECT_EQ(flag_with(worn, "inside the worn tool's 1.00-1.70"), 1);
  EXPECT_EQ(flag_with(worn, "CZII down-cut half: k_f outside the new tool's 0.85-1.15"), 1);
  EXPECT_EQ(flag_with(worn, "CZII up-cut"), 0);
  EXPECT_EQ(flag_with(worn, "new in 0, worn in 6, neither in 0 of 6 cycles"), 1);

  const MonitorReport broken = run(1.0, 3.0, 1.0, 3.0);
  EXPECT_EQ(broken.cycles_neither, 6);
  EXPECT_EQ(flag_with(broken, "inside the worn tool's 1.50-2.30 (Fig. 24) in 0 of them"), 1);

  // Only the down-cut half of CZIII out: the halves are told apart.
  const MonitorReport half = run(1.0, 1.0, 1.0, 1.35);
  EXPECT_EQ(flag_with(half, "CZIII down-cut half"), 1);
  EXPECT_EQ(flag_with(half, "CZIII up-cut half"), 0);
  EXPECT_EQ(flag_with(half, "CZII "), 0);
  EXPECT_EQ(half.cycles_neither, 6);  // CZIII's up-cut 1.0 is below the worn tool's 1.5

  // No criteria: nothing judged.
  Job none = job;
  none.monitor.criteria = KfCriteria::none;
  SynthOptions o;
  o.cycles = 4;
  const MonitorReport off =
      analyze_signal(synth_signal(none, none.monitor, o), none.monitor, &none, o.lead_s);
  for (const auto& c : off.cycles) EXPECT_TRUE(c.judged.empty());

  // Live: the window after each worn cycle says so (the recording ends with the fourth cycle:
  // no window after it, so three).
  SynthOptions lw;
  lw.cycles = 4;
  lw.rate_hz = 48000;
  lw.kf_czii = 1.6;
  lw.kf_cziii = 1.9;
  lw.kf_cziii_down = 1.3;
  const Signal s = synth_signal(job, job.monitor, lw);
  LiveMonitor live(s.rate_hz, job.monitor, &job, lw.lead_s);
  int flagged = 0;
  live.push(s.samples.data(), s.samples.size(), [&](const LiveWindow& w) {
    for (const auto& f : w.flags) flagged += f == "ranges-worn" ? 1 : 0;
  });
  EXPECT_EQ(flagged, 3);
}

// Live monitoring with a job: every window gets the offline analysis' cycle and phase (the
// same planned timing) and the model's zone; on a drifting recording the wear flag appears
// only after the baseline cycles, and ploughing only in CZI windows.
TEST(Signal, LiveMonitorFollowsThePlan) {
  const Job job = pivkin_job();
  SynthOptions o;
  o.cycles = 8;
  o.wear_drift = 1.0;
  o.rate_hz = 48000;
  const Signal s = synth_signal(job, job.monitor, o);
  const MonitorReport off = analyze_signal(s, job.monitor, &job, o.lead_s);
  LiveMonitor live(s.rate_hz, job.monitor, &job, o.lead_s);
  std::vector<LiveWindow> got;
  for (std::size_t i = 0; i < s.samples.size(); i += 4096) {
    live.push(s.samples.data() + i, std::min<std::size_t>(4096, s.samples.size() - i),
              [&](const LiveWindow& w) { got.push_back(w); });
  }
  ASSERT_EQ(got.size(), off.kf.t_s.size());
  int in_cycles = 0, wear_first = -1, ploughing = 0, ploughing_outside_czi = 0;
  for (const LiveWindow& w : got) {
    if (w.cycle < 0) continue;
    ++in_cycles;
    const auto& c = off.cycles[static_cast<std::size_t>(w.cycle)];
    EXPECT_GE(w.window.t_s, c.start_s);
    EXPECT_LT(w.window.t_s, c.end_s);
    EXPECT_NEAR(w.phase, (w.window.t_s - c.start_s) / (c.end_s - c.start_s), 1e-12);
    for (const auto& f : w.flags) {
      if (f == "wear" && wear_first < 0) wear_first = w.cycle;
      if (f == "ploughing") {
        ++ploughing;
        if (w.zone != 1) ++ploughing_outside_czi;
      }
    }
  }
  EXPECT_GT(in_cycles, 1000);
  EXPECT_GT(wear_first, job.monitor.baseline_cycles);  // only after the reference is known
  EXPECT_GT(ploughing, 0);
  EXPECT_EQ(ploughing_outside_czi, 0);
}

// Readers: WAV round trip (float32: 1e-7 relative), CSV with a time column, raw float32 and
// int16; and the errors a user meets.
TEST(Signal, ReadersAndErrors) {
  const auto dir = std::filesystem::temp_directory_path() / "trochomill_signal_test";
  std::filesystem::create_directories(dir);
  Signal s = tones(8000, 0.1, {{440, 0.5}});
  const auto wav = (dir / "a.wav").string();
  write_wav(wav, s);
  const Signal w = read_signal(wav, {});
  ASSERT_EQ(w.samples.size(), s.samples.size());
  EXPECT_EQ(w.rate_hz, 8000);
  for (std::size_t i = 0; i < s.samples.size(); ++i) EXPECT_NEAR(w.samples[i], s.samples[i], 1e-7);
  {
    std::ofstream c(dir / "a.csv");
    c << "t_s,ax,ay\n";
    for (int i = 0; i < 100; ++i) c << i * 1e-4 << "," << i << "," << -i << "\n";
  }
  SignalReadOptions o;
  o.channel = 1;
  const Signal c = read_signal((dir / "a.csv").string(), o);
  EXPECT_NEAR(c.rate_hz, 10000, 1e-6);
  EXPECT_EQ(c.samples[5], -5);
  {
    std::ofstream f(dir / "a.f32", std::ios::binary);
    const float v[3] = {0.25f, -1.5f, 2.0f};
    f.write(reinterpret_cast<const char*>(v), sizeof v);
    std::ofstream h(dir / "a.s16", std::ios::binary);
    const std::int16_t q[2] = {16384, -32768};
    h.write(reinterpret_cast<const char*>(q), sizeof q);
    std::ofstream t(dir / "t.f32", std::ios::binary);
    t.write(reinterpret_cast<const char*>(v), 5);  // a truncated sample
    std::ofstream bad(dir / "bad.csv");
    bad << "1.0\n2.0\nnan\n";
  }
  SignalReadOptions raw;
  raw.rate_hz = 1000;
  EXPECT_EQ(read_signal((dir / "a.f32").string(), raw).samples,
            (std::vector<double>{0.25, -1.5, 2.0}));
  EXPECT_EQ(read_signal((dir / "a.s16").string(), raw).samples, (std::vector<double>{0.5, -1.0}));
  auto message = [&](const std::string& path, const SignalReadOptions& opt) {
    try {
      (void)read_signal(path, opt);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message((dir / "t.f32").string(), raw).find("truncated"), std::string::npos);
  // The option by its API name (the CLI shows --rate: Cli.LibraryOptionsAreNamedByTheirFlags).
  EXPECT_NE(message((dir / "a.f32").string(), {}).find("give rate_hz (Hz)"), std::string::npos);
  EXPECT_NE(message((dir / "bad.csv").string(), raw).find("bad.csv:3:1"), std::string::npos);
  EXPECT_NE(message((dir / "missing.wav").string(), {}).find("cannot"), std::string::npos);
  EXPECT_NE(message(wav,
                    [] {
                      SignalReadOptions x;
                      x.channel = 1;
                      return x;
                    }())
                .find("channel 1"),
            std::string::npos);
  EXPECT_THROW((void)butter_bandpass(4, 5000, 2000, 100000), InputError);
  EXPECT_THROW((void)butter_bandpass(4, 2000, 60000, 100000), InputError);
  MonitorSettings m;
  EXPECT_THROW(validate(m, 20000), InputError);  // 13 kHz above Nyquist
  std::filesystem::remove_all(dir);
}

// Spectra: Welch's PSD integrates to the variance (Parseval, within 1 %: Hann leakage off
// the ends is negligible for a tone in the middle of the band) and peaks at the tone; the
// spectrogram reads the tone's amplitude at a bin-centred frequency within 0.01 dB.
TEST(Signal, SpectrumAndSpectrogram) {
  const double rate = 48000, f = 3000;  // bin-centred for nfft 1024: 3000 = 64 * 46.875
  const Signal s = tones(rate, 2.0, {{f, 0.8}});
  const Spectrum sp = welch(s, 1024);
  double area = 0;
  std::size_t peak = 0;
  for (std::size_t k = 0; k < sp.psd.size(); ++k) {
    area += sp.psd[k] * (rate / 1024);
    if (sp.psd[k] > sp.psd[peak]) peak = k;
  }
  EXPECT_NEAR(area, 0.8 * 0.8 / 2, 0.01 * 0.32);
  EXPECT_NEAR(sp.f_hz[peak], f, 1e-9);
  const Spectrogram sg = spectrogram(s, 1024);
  ASSERT_FALSE(sg.db.empty());
  EXPECT_NEAR(sg.db[3][64], 20 * std::log10(0.8), 0.01);
}

}  // namespace
}  // namespace trochomill
