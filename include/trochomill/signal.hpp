// Vibroacoustic monitoring (Pivkin 2025 Sections 2.3, 4.6, 5.4; docs/models.md section 10): read
// an accelerometer signal, band-pass it into a low (default 2-5 kHz) and a high (8-13 kHz)
// band with Butterworth filters in second-order sections, take windowed RMS values and
// their ratio k_f = RMS_low / RMS_high, cut the signal into trochoid cycles (from the
// planned path's timing or from the signal's own periodicity), set each cycle's k_f profile
// beside the mechanism model's K_re and zones, and flag ploughing and wear. Also: spectra
// and spectrograms for choosing bands, a streaming (causal) monitor, and a synthetic signal
// generator. Times in s, frequencies in Hz.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

#include "trochomill/job.hpp"
#include "trochomill/settings/signal.hpp"

namespace trochomill {

/// One channel of samples at a constant rate.
struct Signal {
  double rate_hz = 0;
  std::vector<double> samples;
  [[nodiscard]] double duration_s() const {
    return rate_hz > 0 ? static_cast<double>(samples.size()) / rate_hz : 0.0;
  }
};

/// How to read a signal file. Formats: `auto` (by extension: .wav .flac .aiff .aif .ogg
/// through libsndfile, .csv, .f32 raw float32, .s16 raw int16), or forced.
enum class SampleFormat { automatic, sndfile, csv, f32, s16 };
[[nodiscard]] SampleFormat parse_sample_format(const std::string& name);  ///< throws InputError

struct SignalReadOptions {
  SampleFormat format = SampleFormat::automatic;
  std::optional<double> rate_hz;  ///< required for raw data and CSV without a time column
  int channel = 0;                ///< 0-based channel of a multichannel file or CSV column
};

/// Reads a signal file ("-" is standard input, raw formats only). CSV: one header line
/// allowed; a column named `t`, `t_s` or `time` gives the time (the rate must be constant
/// within 1e-6 relative); otherwise `rate_hz` is required; `channel` counts the other
/// columns. Throws InputError for unreadable, empty, truncated (raw int16 with an odd byte
/// count, float32 not a multiple of 4) or non-finite data, naming the file and, for CSV,
/// the line.
[[nodiscard]] Signal read_signal(const std::string& path, const SignalReadOptions& opt);
/// Decodes `count` raw little-endian samples (float32, or int16 scaled to [-1, 1)).
void decode_raw(const unsigned char* bytes, std::size_t count, SampleFormat f, double* out);
/// Writes a mono float32 WAV (the caller makes it atomic). Throws Error on failure.
void write_wav(const std::string& path, const Signal& s);

/// A cascade of second-order sections, each {b0, b1, b2, 1, a1, a2} (scipy's layout).
struct Sos {
  std::vector<std::array<double, 6>> sections;
};

/// Butterworth band-pass of the given order (the low-pass prototype's: the filter has
/// 2 * order poles and `order` sections), band edges in Hz (-3 dB), bilinear transform with
/// pre-warped edges (as scipy.signal.butter(order, [lo, hi], 'bandpass', fs=rate,
/// output='sos')). Throws InputError unless 1 <= order <= 12 and 0 < lo < hi < rate / 2.
[[nodiscard]] Sos butter_bandpass(int order, double lo_hz, double hi_hz, double rate_hz);
/// Butterworth low-pass of the given order, cutoff in Hz (-3 dB), bilinear transform with a
/// pre-warped cutoff (as scipy.signal.butter(order, cutoff, fs=rate, output='sos'), up to the
/// sections' order and gain split). Throws InputError unless 1 <= order <= 12 and
/// 0 < cutoff < rate / 2.
[[nodiscard]] Sos butter_lowpass(int order, double cutoff_hz, double rate_hz);
/// |H(e^{i 2 pi f / rate})| of the cascade.
[[nodiscard]] double sos_gain(const Sos& sos, double f_hz, double rate_hz);

/// Causal filtering, transposed direct form II per section; keeps its state between calls,
/// so feeding a signal in pieces gives exactly the output of feeding it whole.
class SosFilter {
 public:
  explicit SosFilter(Sos sos);
  [[nodiscard]] double step(double x);
  void process(const double* in, double* out, std::size_t n);
  /// `a` and `b` over the same block in one pass, each from its state on (the live
  /// monitor's two bands): equal to a.process and b.process bit for bit, at about the cost
  /// of one. Filters of different section counts run one after the other.
  static void process_pair(SosFilter& a, SosFilter& b, const double* in, double* out_a,
                           double* out_b, std::size_t n);
  void reset();

 private:
  Sos sos_;
  std::vector<std::array<double, 2>> z_;
};
[[nodiscard]] std::vector<double> sosfilt(const Sos& sos, const std::vector<double>& x);
/// Zero-phase filtering: forward and backward with odd extension of 3 (2 n_sections + 1)
/// samples at each end and steady-state initial conditions (scipy.signal.sosfiltfilt's
/// defaults); the magnitude response is |H|^2.
[[nodiscard]] std::vector<double> sosfiltfilt(const Sos& sos, const std::vector<double>& x);

/// Two filters over the same input in one pass (twice the independent work per sample, so
/// about the cost of one): causal, and zero-phase as sosfiltfilt. Results equal the single
/// versions bit for bit.
void sosfilt_pair(const Sos& a, const Sos& b, const std::vector<double>& x, std::vector<double>& ya,
                  std::vector<double>& yb);
void sosfiltfilt_pair(const Sos& a, const Sos& b, const std::vector<double>& x,
                      std::vector<double>& ya, std::vector<double>& yb);
/// One filter, zero-phase, over three signals (the x, y and z of a force) in one pass, in
/// place: the three recursions side by side cost about one. Results equal sosfiltfilt's on
/// each bit for bit; signals of different lengths are filtered one by one.
void sosfiltfilt_three(const Sos& sos, std::array<std::vector<double>, 3>& xyz);

/// Welch power spectral density (Hann window, 50 % overlap, one-sided, units^2 / Hz).
struct Spectrum {
  std::vector<double> f_hz, psd;
};
[[nodiscard]] Spectrum welch(const Signal& s, int nfft);
/// Short-time Fourier transform magnitude in dB (Hann window, hop nfft / 2): frames x bins.
struct Spectrogram {
  std::vector<double> t_s, f_hz;
  std::vector<std::vector<double>> db;  ///< [frame][bin], 20 log10 |X| (amplitude)
};
[[nodiscard]] Spectrogram spectrogram(const Signal& s, int nfft);

/// MonitorSettings (settings/signal.hpp) are `[monitor]` in the job, validated by load_job; this
/// checks them against a signal's rate. Throws InputError naming the setting.
void validate(const MonitorSettings& m, double rate_hz);

/// k_f over time: windows of `window_s` (the last partial window dropped), window k covering
/// [k w, (k + 1) w) and stamped at its centre.
struct KfSeries {
  double window_s = 0;
  std::vector<double> t_s, rms_low, rms_high, k_f;
};
/// Offline (zero_phase: forward-backward filters) or causal.
[[nodiscard]] KfSeries kf_series(const Signal& s, const MonitorSettings& m, bool zero_phase);

/// Live monitor: causal filters, one result per completed window (latency: one window).
class KfStream {
 public:
  struct Window {
    double t_s = 0;  ///< window centre from the stream's start
    double rms_low = 0, rms_high = 0, k_f = 0;
  };
  KfStream(double rate_hz, const MonitorSettings& m);
  /// Feeds samples; calls `on_window` for every window they complete.
  void push(const double* x, std::size_t n, const std::function<void(const Window&)>& on_window);

 private:
  double rate_hz_;
  std::size_t window_n_, filled_ = 0, index_ = 0;
  SosFilter low_, high_;
  double sum_low_ = 0, sum_high_ = 0;
  std::vector<double> y_low_, y_high_;  // a block's filtered samples
  void accumulate(std::size_t n, const std::function<void(const Window&)>& on_window);
};

/// Where the cycles are: start times and period; from the job or found in the signal.
struct CycleTiming {
  std::string source;           ///< "job" or "signal"
  std::vector<double> start_s;  ///< start of every whole cycle in the signal
  std::vector<double> end_s;    ///< and its end
  double period_s = 0;          ///< mean cycle time
  std::string note;             ///< why there are no cycles (a signal without a period)
};
/// The planned program's cycle boundaries (s from the program start, programmed feeds): n + 1
/// values for n cycles, the last cycle lasting as long as the one before it. Throws
/// InputError when the plan has fewer than two cycles.
[[nodiscard]] std::vector<double> planned_cycle_bounds(const Job& job);
/// From the planned path: cycle k starts at `start_s` + its programmed time (feeds at the
/// programmed rate; acceleration ignored). Only cycles wholly inside the signal.
[[nodiscard]] CycleTiming cycles_from_job(const Job& job, double start_s, double duration_s);
/// From the k_f series alone: the period is the first strong maximum of the broadband RMS
/// envelope's autocorrelation (between min_period_s and max_period_s; refined by parabolic
/// interpolation); each cycle starts at the envelope's steepest rise (the cut's onset, which
/// the mechanism model may put a little before theta = 0) within a quarter period of the
/// folded estimate; only cycles in which the envelope gets loud count. When no period stands
/// out (a flat or too short signal, an autocorrelation peak below 0.3, as noise gives) there
/// are no cycles and `note` says why.
[[nodiscard]] CycleTiming cycles_from_signal(const KfSeries& kf, double min_period_s,
                                             double max_period_s);

/// The mechanism model beside the signal: zone (0 air, 1-3 CZI-III) and K_re at each of
/// `phase_bins` phases of a cycle (phase = time since the cycle start / cycle time), and the
/// half of the cut each falls in (1 the first, up-cut half; 2 the second, down-cut half; 0
/// not cutting): the cut's span from its start to its end, pauses included, halved.
struct ModelProfile {
  std::vector<double> k_re_pct;
  std::vector<int> zone;
  std::vector<int> half;
};
/// The half of the cut (1 first, 2 second, 0 not cutting) at `t_s` into a cycle of the
/// mechanism curve whose zones `z` summarises (cycle time `cycle_s`).
[[nodiscard]] int cut_half(double t_s, int zone, double cutting_start_s, double cutting_span_s,
                           double cycle_s);

/// A k_f range (lo..hi, inclusive) of Pivkin 2025's monitoring criteria.
struct KfRange {
  double lo = 0, hi = 0;
  [[nodiscard]] bool contains(double v) const { return v >= lo && v <= hi; }
};
/// Pivkin 2025's k_f ranges for zone CZII (`zone` 2) or CZIII (3) in the cut's first half
/// (`half` 1, up-cut) or second (2, down-cut): a new tool (Fig. 21, stage TI: CZII 0.85-1.15,
/// CZIII 1 +- 10 %) and a worn one (Fig. 24, stage TIII: CZII 0.7-1, up to 2.5; CZIII 1.5-2.3
/// until the middle of the cut, 1-1.7 after it). CZI has no range (k_f follows K_re there).
[[nodiscard]] KfRange pivkin2025_kf_range(int zone, int half, bool worn);

/// One zone and half of the cut of a cycle, judged against the ranges.
struct KfJudgement {
  int zone = 0;     ///< 2 CZII, 3 CZIII
  int half = 0;     ///< 1 first (up-cut), 2 second (down-cut)
  double k_f = 0;   ///< mean k_f of the windows there
  int windows = 0;  ///< how many
  KfRange new_range, worn_range;
  bool in_new = false, in_worn = false;
};
/// The fewest windows a (zone, half) cell is judged on: one 5 ms window's k_f scatters by
/// ~18 % on noise-like signals, five windows' mean by ~8 %, about half the new tool's CZII
/// range (+-15 %). A zone that brief in a half (CZII at the cut's start, where the chip grows
/// fast) is not judged in that cycle.
inline constexpr int kKfMinWindows = 5;
/// Judges the mean k_f of each (zone, half) cell; `sum` and `count` indexed [zone - 2][half -
/// 1]. Cells with fewer than kKfMinWindows windows are left out.
[[nodiscard]] std::vector<KfJudgement> judge_kf(const double sum[2][2], const double count[2][2]);
/// What the judged cells say: "new" (all inside the new tool's ranges), "worn" (all inside the
/// worn tool's, not all the new's), "neither", or "" with no cell judged.
[[nodiscard]] std::string kf_tool_state(const std::vector<KfJudgement>& judged);
/// "CZIII up-cut" and the like.
[[nodiscard]] std::string kf_cell_name(int zone, int half);
/// The job's mechanism model (mechanism_settings(job)) at `bins` phases of its steady-state
/// cycle (bin centres; phase 0 is theta = 0).
[[nodiscard]] ModelProfile model_profile(const Job& job, int bins);

struct CycleResult {
  double start_s = 0, end_s = 0;
  double k_f_mean = 0;              ///< over the cutting part where the model is known, else all
  std::vector<double> k_f_profile;  ///< per phase bin (NaN where no window fell)
  std::optional<double> k_f_czi, k_f_cziii;  ///< mean k_f in the zone's phases (with a job)
  bool ploughing = false;                    ///< k_f_czi > ploughing_ratio * k_f_cziii
  bool wear = false;                         ///< k_f_mean > wear_ratio * reference level
  /// With a job and criteria: each zone and half of the cut against the ranges, and what
  /// they say of the tool ("new", "worn", "neither"; "" where nothing was judged).
  std::vector<KfJudgement> judged;
  std::string tool_state;
};

struct MonitorReport {
  KfSeries kf;
  CycleTiming timing;
  std::optional<ModelProfile> model;
  std::vector<CycleResult> cycles;
  double k_f_mean = 0;       ///< mean over the cycles' k_f_mean (over all windows without cycles)
  double reference_k_f = 0;  ///< mean k_f level of the first baseline_cycles cycles
  bool wear_trend = false;   ///< the last baseline_cycles cycles' level > wear_ratio * reference
  /// With criteria: how many cycles the ranges call new, worn and neither.
  int cycles_new = 0, cycles_worn = 0, cycles_neither = 0;
  std::vector<std::string> flags;  ///< human-readable, one per finding
  /// What limits the result (no period in the signal: no cycles, the mean over all windows).
  std::vector<std::string> warnings;
};

/// The whole offline analysis. With `job` the cycles come from its planned path and
/// `start_s` (s into the recording where the program starts) and the model's zones give the
/// ploughing flag; without, from the signal's periodicity (period between 0.02 and 20 s).
[[nodiscard]] MonitorReport analyze_signal(const Signal& s, const MonitorSettings& m,
                                           const Job* job, double start_s);

/// Synthetic signal for tests and demos: per cycle of the job's steady-state trochoid, noise
/// bands whose RMS ratio follows k_f(phase) = the zone's value (CZI `kf_czi`, CZII `kf_czii`,
/// CZIII `kf_cziii`; air: amplitude `idle`), a slow drift multiplying k_f by 1 + wear_drift
/// times the fraction of the way from the first cycle's start to the last cycle's end, and
/// white noise. The recording starts `lead_s` before the program (its `--start`).
struct SynthOptions {
  double rate_hz = 100000;
  int cycles = 12;
  /// k_f per zone (the up-cut half's where the halves differ): CZII and CZIII in the middle of
  /// Pivkin 2025's new-tool ranges, CZI above them (k_f rises there with K_re).
  double kf_czi = 1.6, kf_czii = 1.0, kf_cziii = 1.0;
  /// k_f of CZII and CZIII in the cut's second (down-cut) half; absent: as in the first.
  std::optional<double> kf_czii_down, kf_cziii_down;
  double idle = 0.05;     ///< band amplitude in air, relative to cutting
  double noise = 0.02;    ///< white noise RMS, relative to the cutting band RMS
  double wear_drift = 0;  ///< k_f x (1 + wear_drift) by the last cycle's end
  double lead_s = 0.1;    ///< air before the first cycle (the program start)
  std::uint32_t seed = 1;
};
/// `cycles_covered`, if given, receives the cycles the signal covers: `o.cycles`, or all the
/// planned program has when it has fewer.
[[nodiscard]] Signal synth_signal(const Job& job, const MonitorSettings& m, const SynthOptions& o,
                                  int* cycles_covered = nullptr);
/// The memory synth_signal will use (bytes), before running it.
[[nodiscard]] double synth_signal_memory_bytes(const Job& job, const SynthOptions& options);

/// Live monitoring: a KfStream and, with a job, each window's cycle, phase and zone from the
/// planned timing (cycle k starts at start_s + its programmed start) with running flags:
/// "ploughing" when a CZI window's k_f exceeds ploughing_ratio times the running mean of the
/// CZIII windows so far (after 10 of them), "wear" once the last finished cycle's k_f level
/// exceeds wear_ratio times the first baseline_cycles cycles' level, and with criteria, on the
/// first window after a cycle whose zones and halves leave the new tool's ranges,
/// "ranges-worn" (all inside the worn tool's) or "ranges-neither".
struct LiveWindow {
  KfStream::Window window;
  int cycle = -1;     ///< -1 outside the planned cycles or without a job
  double phase = -1;  ///< 0..1 within the cycle
  int zone = -1;      ///< model zone (0 air, 1-3 CZI-III); -1 unknown
  int half = -1;      ///< half of the cut (1 up-cut, 2 down-cut, 0 not cutting); -1 unknown
  std::vector<std::string> flags;
};
class LiveMonitor;
/// Feeds a live monitor from a stream of samples until its end (`--stream`): raw f32 or s16
/// (native byte order) or CSV (one number per line, '#' lines skipped). `out` is called for
/// each completed window. Throws InputError naming the sample or line that is not a finite
/// number, or a truncated last sample. Memory stays bounded (4096 samples at a time).
void monitor_stream(std::FILE* in, SampleFormat format, LiveMonitor& live,
                    const std::function<void(const LiveWindow&)>& out);

/// The `count` strongest peaks (local maxima) of a spectrum, strongest first (bin indices).
[[nodiscard]] std::vector<std::size_t> spectrum_peaks(const Spectrum& sp, std::size_t count);

class LiveMonitor {
 public:
  LiveMonitor(double rate_hz, const MonitorSettings& m, const Job* job, double start_s);
  void push(const double* x, std::size_t n, const std::function<void(const LiveWindow&)>& out);

 private:
  MonitorSettings m_;
  KfStream stream_;
  std::vector<double> bounds_;  ///< cycle boundaries in stream time (empty without a job)
  std::vector<int> zone_;       ///< model zones per phase bin
  std::vector<int> half_;       ///< and the half of the cut (1, 2; 0 not cutting)
  double cell_sum_[2][2] = {{0, 0}, {0, 0}}, cell_n_[2][2] = {{0, 0}, {0, 0}};
  int cycle_ = -1;
  double cycle_sum_ = 0, cycle_n_ = 0, ref_sum_ = 0, cziii_sum_ = 0, cziii_n_ = 0;
  int finished_ = 0;
  double last_level_ = 0;
};

}  // namespace trochomill
