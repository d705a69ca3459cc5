// The CLI's signal commands: monitor of a recording without a period, and monitor,
// synth-signal and spectrum round trips, live and with bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_util.hpp"
#include "test_util.hpp"
#include "trochomill/signal.hpp"

namespace trochomill {
namespace {

using test::Cli;
using test::CliResult;
using test::run_cli;

// 0.1 s at 48 kHz of 3162 Hz and 10198 Hz tones as raw little-endian float32.
void tmill_signal_file(const std::filesystem::path& p) {
  std::ofstream f(p, std::ios::binary);
  for (int i = 0; i < 4800; ++i) {
    const double t = i / 48000.0;
    const auto v = static_cast<float>(0.7 * std::sin(2 * M_PI * 3162.3 * t) +
                                      0.4 * std::sin(2 * M_PI * 10198 * t));
    f.write(reinterpret_cast<const char*>(&v), sizeof v);  // x86-64 and arm64: little-endian
  }
}

// A recording without a period (a flat line, white noise) is still a result: the k_f series
// and its mean, no cycles, a warning saying why, exit 0.
TEST_F(Cli, MonitorWithoutAPeriodReportsTheSeries) {
  const auto flat = (dir_ / "flat.f32").string(), noise = (dir_ / "noise.s16").string();
  {
    std::ofstream f(flat, std::ios::binary);
    const std::vector<float> zeros(200000, 0.0f);  // 2 s at 100 kHz
    f.write(reinterpret_cast<const char*>(zeros.data()),
            static_cast<std::streamsize>(zeros.size() * sizeof(float)));
    std::ofstream n(noise, std::ios::binary);
    std::uint32_t state = 12345;  // a fixed LCG: white noise, the same every run
    for (int i = 0; i < 200000; ++i) {
      state = state * 1664525u + 1013904223u;
      const auto v = static_cast<std::int16_t>(static_cast<std::int32_t>(state >> 16) - 32768);
      n.write(reinterpret_cast<const char*>(&v), sizeof v);
    }
  }
  const CliResult a = run_cli("monitor " + flat + " --rate 100000 --json -");
  ASSERT_EQ(a.code, 0) << a.out;
  EXPECT_NE(a.out.find("warning: the signal"), std::string::npos) << a.out;
  const auto ja = nlohmann::json::parse(a.out.substr(a.out.find('{')));
  EXPECT_EQ(ja["cycles"].get<int>(), 0);
  EXPECT_TRUE(ja["k_f_mean"].is_null());  // 0 / 0 in every window: no level to report
  EXPECT_EQ(ja["warnings"].size(), 1u);

  const auto csv = (dir_ / "noise.csv").string();
  const CliResult b = run_cli("monitor " + noise + " --rate 100000 --json - --csv " + csv);
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_NE(b.out.find("warning: no cycle period stands out"), std::string::npos) << b.out;
  const auto jb = nlohmann::json::parse(b.out.substr(b.out.find('{')));
  EXPECT_EQ(jb["cycles"].get<int>(), 0);
  // White noise has a flat spectrum: the band RMS ratio is sqrt of the bandwidth ratio,
  // sqrt(3000 / 5000) = 0.775 for the default bands (2-5 kHz over 8-13 kHz); within 10 %
  // for the filters' skirts and the estimate's spread over 0.4 M samples.
  EXPECT_NEAR(jb["k_f_mean"].get<double>(), std::sqrt(3000.0 / 5000.0), 0.08);
  std::ifstream in(csv);
  std::size_t rows = 0;
  for (std::string line; std::getline(in, line);) ++rows;
  EXPECT_GT(rows, 10u);  // the per-window series is written
}

// monitor, synth-signal, spectrum: a synthetic recording round trip with the required JSON
// keys, the live stream (one JSON line per window, equal to the library's causal series),
// and bad input (exit 2).
TEST_F(Cli, MonitorSynthAndSpectrum) {
  const auto ex = test::example("pivkin2025/trochoidal.toml").string();
  const auto wav = (dir_ / "s.wav").string();
  CliResult r = run_cli("synth-signal " + ex + " -o " + wav + " --cycles 4 --rate 48000");
  ASSERT_EQ(r.code, 0) << r.out;
  r = run_cli("monitor " + wav + " --job " + ex + " --start 0.1 --json -");
  ASSERT_EQ(r.code, 0) << r.out;
  auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["cycles"], 4);
  EXPECT_EQ(j["k_f_per_cycle"].size(), 4u);
  EXPECT_GT(j["k_f_mean"].get<double>(), 0.9);
  EXPECT_LT(j["k_f_mean"].get<double>(), 1.3);
  EXPECT_TRUE(j["flags"].is_array());
  EXPECT_EQ(j["cycle_source"], "job");
  r = run_cli("monitor " + wav + " --json -");  // cycles from the signal alone
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out)["cycle_source"], "signal");
  r = run_cli("spectrum " + wav + " --nfft 1024 --csv -");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_EQ(r.out.rfind("f_hz,psd_per_hz\n", 0), 0u);

  // Live: raw float32 on stdin, 0.1 s of a tone pair at 48 kHz: 20 windows of 5 ms.
  tmill_signal_file(dir_ / "x.f32");
  r = run_cli("monitor --stream --rate 48000 < " + (dir_ / "x.f32").string());
  ASSERT_EQ(r.code, 0) << r.out;
  std::vector<nlohmann::json> lines;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) lines.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(lines.size(), 20u);
  const Signal sig = read_signal((dir_ / "x.f32").string(), [] {
    SignalReadOptions o;
    o.rate_hz = 48000;
    return o;
  }());
  const KfSeries causal = kf_series(sig, MonitorSettings{}, false);
  for (std::size_t i = 0; i < lines.size(); ++i) {
    EXPECT_NEAR(lines[i]["k_f"].get<double>(), causal.k_f[i], 1e-12 * causal.k_f[i]);
  }

  // Bad input.
  EXPECT_EQ(run_cli("monitor " + (dir_ / "x.f32").string()).code, 2);  // no rate
  EXPECT_EQ(run_cli("monitor " + wav + " --low 5000:2000").code, 2);
  EXPECT_EQ(run_cli("monitor " + wav + " --high 8000:30000").code, 2);  // above Nyquist
  EXPECT_EQ(run_cli("monitor " + (dir_ / "none.wav").string()).code, 2);
  {
    std::ofstream t(dir_ / "t.f32", std::ios::binary);
    t.write("abcde", 5);
  }
  r = run_cli("monitor --stream --rate 48000 < " + (dir_ / "t.f32").string());
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("truncated"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad.wav"));
  EXPECT_EQ(
      run_cli("synth-signal " + ex + " -o " + (dir_ / "bad.wav").string() + " --rate -5").code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad.wav"));
}

}  // namespace
}  // namespace trochomill
