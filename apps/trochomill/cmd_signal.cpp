// monitor, synth-signal and spectrum: Pivkin 2025's vibroacoustic k_f monitor (offline or
// live), a synthetic recording that follows the model's zones, and the spectrum of a signal.
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <memory>
#include <optional>

#include "cli_common.hpp"
#include "commands.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report/signal.hpp"
#include "trochomill/signal.hpp"

namespace trochomill::cli {
namespace {

// A band flag LOW:HIGH sets two [monitor] keys (band_min, band_max): an alias like the others.
void add_band_alias(CLI::App* cmd, JobArgs& job, const std::string& flag, const std::string& band,
                    const std::string& default_text) {
  cmd->add_option_function<std::string>(
      flag,
      [&job, flag, band](const std::string& v) {
        const auto [lo, hi] = parse_band(flag, v);
        job.aliases.push_back({flag, "monitor." + band + "_min", fmt::format("{}", lo)});
        job.aliases.push_back({flag, "monitor." + band + "_max", fmt::format("{}", hi)});
      },
      fmt::format("{} band LOW:HIGH, Hz (the job keys monitor.{}_min, {}_max; default {})", band,
                  band, band, default_text));
}

}  // namespace

void register_signal_commands(CLI::App& app, int& exit_code) {
  // monitor
  {
    struct Args {
      SignalArgs signal;
      JobArgs job;
      std::string json, csv;
      double start_s = 0;
      bool stream = false;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "monitor", "vibroacoustic k_f = RMS(low band) / RMS(high band) per trochoid cycle, flags");
    add_signal_args(cmd, a->signal, false);
    cmd->add_option("--job", a->job.file,
                    "job file: cycle timing, [monitor] settings, model zones");
    cmd->add_option("--set", a->job.sets, "override a job key (repeatable)")->take_all();
    cmd->add_option("--start", a->start_s, "time in the signal where the program starts, s")
        ->check(finite_in(0, 1e9));
    add_band_alias(cmd, a->job, "--low", "low", "2000:5000");
    add_band_alias(cmd, a->job, "--high", "high", "8000:13000");
    add_key_alias(cmd, a->job, "--order", "monitor.order", "Butterworth order per band");
    add_key_alias(cmd, a->job, "--window", "monitor.window", "RMS window, s");
    cmd->add_option("--json", a->json, "write the results as JSON (- for stdout)");
    cmd->add_option("--csv", a->csv, "write the per-window series as CSV (- for stdout)");
    cmd->add_flag("--stream", a->stream,
                  "live: read samples from stdin (--format f32, s16 or csv; --rate), one JSON "
                  "line per window");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->json, &a->csv}, {&a->signal.file, &a->job.file});
      std::optional<Job> job;
      MonitorSettings m;
      if (!a->job.file.empty()) {
        job = a->job.load();
        m = job->monitor;
      } else {
        if (!a->job.sets.empty()) throw InputError("--set needs --job");
        Job defaults;  // no job file: the band flags set the default settings
        apply_overrides(defaults, a->job.overrides());
        m = defaults.monitor;
      }
      exit_code = 0;
      if (a->stream) {
        if (!a->signal.file.empty() && a->signal.file != "-")
          throw InputError("--stream reads stdin: give no SIGNAL (or -)");
        if (!a->signal.rate) throw InputError("--stream needs --rate (Hz)");
        const SampleFormat f =
            parse_sample_format(a->signal.format == "auto" ? "f32" : a->signal.format);
        LiveMonitor live(*a->signal.rate, m, job ? &*job : nullptr, a->start_s);
        monitor_stream(stdin, f, live, [](const LiveWindow& w) {
          const std::string line = live_json_line(w);
          std::fwrite(line.data(), 1, line.size(), stdout);
          std::fflush(stdout);  // one line per window, as soon as it completes
        });
        return;
      }
      if (a->signal.file.empty()) throw InputError("monitor: give a SIGNAL file (or --stream)");
      const Signal sig = a->signal.read();
      const MonitorReport r = analyze_signal(sig, m, job ? &*job : nullptr, a->start_s);
      for (const std::string& w : r.warnings) fmt::print(stderr, "warning: {}\n", w);
      if (!a->json.empty()) emit(a->json, monitor_json(r, a->signal.file, sig, m));
      if (!a->csv.empty()) emit(a->csv, monitor_csv(r));
      if (summary_to_stdout({&a->json, &a->csv})) {
        fmt::print("{}", monitor_table(r, a->signal.file, sig));
      }
    });
  }
  // synth-signal
  {
    struct Args {
      JobArgs job;
      std::string out;
      SynthOptions synth;
      std::optional<double> memory_gb;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand(
        "synth-signal", "synthetic vibroacoustic signal following the model's zones (WAV)");
    add_job_args(cmd, a->job);
    SynthOptions& syn = a->synth;
    cmd->add_option("-o,--output", a->out, "output WAV file (- for stdout)")->required();
    add_memory_limit(cmd, a->memory_gb);
    cmd->add_option("--rate", syn.rate_hz, "sample rate, Hz")
        ->capture_default_str()
        ->check(finite_above(0, 1e7));
    cmd->add_option("--cycles", syn.cycles, "trochoid cycles to cover")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--kf-czi", syn.kf_czi, "k_f in CZI")
        ->capture_default_str()
        ->check(finite_above(0, 100));
    cmd->add_option("--kf-czii", syn.kf_czii,
                    "k_f in CZII (the cut's up-cut half, and both without --kf-czii-down)")
        ->capture_default_str()
        ->check(finite_above(0, 100));
    cmd->add_option("--kf-cziii", syn.kf_cziii,
                    "k_f in CZIII (the cut's up-cut half, and both without --kf-cziii-down)")
        ->capture_default_str()
        ->check(finite_above(0, 100));
    cmd->add_option("--kf-czii-down", syn.kf_czii_down,
                    "k_f in CZII in the cut's second (down-cut) half (default: --kf-czii)")
        ->check(finite_above(0, 100));
    cmd->add_option("--kf-cziii-down", syn.kf_cziii_down,
                    "k_f in CZIII in the cut's second (down-cut) half (default: --kf-cziii)")
        ->check(finite_above(0, 100));
    cmd->add_option("--wear-drift", syn.wear_drift,
                    "k_f grows by this fraction from the first cycle to the last")
        ->capture_default_str()
        ->check(finite_in(0, 100));
    cmd->add_option("--noise", syn.noise, "white noise RMS relative to cutting")
        ->capture_default_str()
        ->check(finite_in(0, 100));
    cmd->add_option("--lead", syn.lead_s, "air before the program start, s")
        ->capture_default_str()
        ->check(finite_in(0, 1e4));
    cmd->add_option("--seed", syn.seed, "random seed")->capture_default_str();
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->out}, {&a->job.file});
      const std::string ext = lower_extension(a->out);
      if (ext != ".wav" && a->out != "-") {
        throw InputError(fmt::format("-o {}: synth-signal writes WAV: give a .wav file", a->out));
      }
      const Job job = a->job.load();
      check_memory("synth-signal", synth_signal_memory_bytes(job, a->synth), a->memory_gb,
                   fmt::format("lower --rate (now {:g} Hz) or --cycles (now {})", a->synth.rate_hz,
                               a->synth.cycles));
      // The program may have fewer cycles than asked for: say how many the signal covers.
      int cycles = 0;
      const Signal sig = synth_signal(job, job.monitor, a->synth, &cycles);
      // libsndfile writes WAV to a seekable file: for "-" a temporary one, then stdout.
      emit_file(a->out, ".wav",
                [&](const std::filesystem::path& tmp) { write_wav(tmp.string(), sig); });
      // With the WAV on stdout the summary goes to stderr.
      fmt::print(a->out == "-" ? stderr : stdout,
                 "{}: {:.3f} s at {:g} Hz, {} cycles{} from the program start at {:g} s -> {}\n",
                 a->job.file, sig.duration_s(), sig.rate_hz, cycles,
                 cycles < a->synth.cycles
                     ? fmt::format(" (all the program has; {} asked for)", a->synth.cycles)
                     : "",
                 a->synth.lead_s, a->out);
      exit_code = 0;
    });
  }
  // spectrum
  {
    struct Args {
      SignalArgs signal;
      int nfft = 4096;
      std::string csv, spectrogram;
    };
    auto a = std::make_shared<Args>();
    auto* cmd = app.add_subcommand("spectrum", "Welch spectrum and spectrogram, to choose bands");
    add_signal_args(cmd, a->signal, true);
    cmd->add_option("--nfft", a->nfft, "FFT length, a power of two")
        ->capture_default_str()
        ->check(CLI::Range(16, 1 << 24));
    cmd->add_option("--csv", a->csv, "write the PSD as CSV (- for stdout)");
    cmd->add_option("--spectrogram", a->spectrogram,
                    "write the spectrogram as CSV (t_s, f_hz, db)");
    cmd->final_callback([a, &exit_code] {
      check_outputs({&a->csv, &a->spectrogram}, {&a->signal.file});
      const Signal sig = a->signal.read();
      const Spectrum sp = welch(sig, a->nfft);
      if (!a->csv.empty()) emit(a->csv, spectrum_csv(sp));
      if (!a->spectrogram.empty()) {
        emit(a->spectrogram, spectrogram_csv(spectrogram(sig, a->nfft)));
      }
      // The summary only where it does not mix into a CSV on stdout.
      if (summary_to_stdout({&a->csv, &a->spectrogram})) {
        fmt::print("{}", spectrum_text(a->signal.file, sig, sp, a->nfft));
      }
      exit_code = 0;
    });
  }
}

}  // namespace trochomill::cli
