// Settings of the signal module's vibroacoustic monitor (signal.hpp): `[monitor]` in the job
// (src/job/schema.cpp holds the keys, units and ranges; the CLI's band flags override them).
#pragma once

namespace trochomill {

/// Ranges the monitor judges each cycle's k_f against (docs/models.md section 10).
enum class KfCriteria {
  none,        ///< no ranges: the ploughing and wear flags only
  pivkin2025,  ///< Pivkin 2025's ranges per zone and half of the cut, new tool (Fig. 21) and
               ///< worn tool (Fig. 24)
};

/// Pivkin 2025's k_f = RMS(low band) / RMS(high band) monitor. Frequencies in Hz, times in s.
struct MonitorSettings {
  double low_min_hz = 2000, low_max_hz = 5000;     ///< low band (Hz)
  double high_min_hz = 8000, high_max_hz = 13000;  ///< high band (Hz)
  int order = 4;                                   ///< Butterworth order of each band
  double window_s = 0.005;                         ///< RMS window (and hop) (s)
  int baseline_cycles = 3;  ///< wear: cycles whose k_f level is the reference
  double wear_ratio = 1.3;  ///< wear flagged where the k_f level exceeds the reference by this
  double ploughing_ratio = 1.15;  ///< ploughing flagged where k_f in CZI exceeds CZIII's by this
  int phase_bins = 50;            ///< k_f profile bins over a cycle
  KfCriteria criteria = KfCriteria::pivkin2025;  ///< with a job: the k_f ranges judged
};

}  // namespace trochomill
