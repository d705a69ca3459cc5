// Surface texture of a profile: the ISO 16610-21 Gaussian filter and the ISO 21920-2 profile
// parameters (texture.hpp; docs/models.md section "Surface texture").
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "texture/gaussian.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/texture.hpp"

namespace trochomill {

using detail::gaussian_weights;
using detail::kernel_half;

namespace {

// alpha = sqrt(ln 2 / pi): the Gaussian whose transmission is 50 % at the cut-off.
const double kAlpha = std::sqrt(std::numbers::ln2 / std::numbers::pi);

void check_profile(const std::vector<double>& z_mm, double dx_mm, const char* what) {
  if (!(std::isfinite(dx_mm) && dx_mm > 0)) {
    throw InputError(
        fmt::format("{}: the sample spacing must be a finite number > 0 mm, got {}", what, dx_mm));
  }
  for (std::size_t i = 0; i < z_mm.size(); ++i) {
    if (!std::isfinite(z_mm[i])) {
      throw InputError(
          fmt::format("{}: height {} (sample {}) is not a finite number", what, z_mm[i], i));
    }
  }
}

}  // namespace

namespace detail {

std::size_t kernel_half(double dx_mm, double cutoff_mm) {
  const double half = std::floor(cutoff_mm / dx_mm);
  if (!(half <= kMaxKernelHalf)) {
    throw InputError(fmt::format(
        "Gaussian filter: a {:g} mm cut-off at {:g} mm spacing spans {:.3g} samples (limit "
        "{:.3g}); resample the profile coarser or give a shorter cut-off",
        cutoff_mm, dx_mm, 2 * half + 1, 2 * kMaxKernelHalf + 1));
  }
  return static_cast<std::size_t>(half);
}

// s(x) = exp(-pi (x / (alpha lambda_c))^2) / (alpha lambda_c) on 2 half + 1 samples, normalised
// to sum to one (the discrete sum of a Gaussian this wide against its spacing is its integral
// to far below rounding).
std::vector<double> gaussian_weights(double dx_mm, double cutoff_mm, std::size_t reach) {
  const std::size_t half = std::min(kernel_half(dx_mm, cutoff_mm), reach);
  std::vector<double> w(2 * half + 1);
  double sum = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    const double x = (static_cast<double>(k) - static_cast<double>(half)) * dx_mm;
    const double u = x / (kAlpha * cutoff_mm);
    w[k] = std::exp(-std::numbers::pi * u * u);
    sum += w[k];
  }
  for (double& v : w) v /= sum;
  return w;
}

}  // namespace detail

double gaussian_transmission(double lambda_mm, double cutoff_mm) {
  const double r = kAlpha * cutoff_mm / lambda_mm;
  return std::exp(-std::numbers::pi * r * r);
}

namespace {

// out[i] = sum over k of w[k] z[i + k], i < count, each sum in the order of k (the bits of a
// plain loop): four outputs at a time, so four chains of additions run side by side instead
// of each waiting on the last (the mean lines' filters were a seventh of `analyze`).
void correlate(const std::vector<double>& w, const double* z, double* out, std::size_t count) {
  const std::size_t nw = w.size();
  const double* wp = w.data();
  std::size_t i = 0;
  for (; i + 4 <= count; i += 4) {
    double m0 = 0, m1 = 0, m2 = 0, m3 = 0;
    const double* zi = z + i;
    for (std::size_t k = 0; k < nw; ++k) {
      const double wk = wp[k];
      m0 += wk * zi[k];
      m1 += wk * zi[k + 1];
      m2 += wk * zi[k + 2];
      m3 += wk * zi[k + 3];
    }
    out[i] = m0;
    out[i + 1] = m1;
    out[i + 2] = m2;
    out[i + 3] = m3;
  }
  for (; i < count; ++i) {
    double m = 0;
    for (std::size_t k = 0; k < nw; ++k) m += wp[k] * z[i + k];
    out[i] = m;
  }
}

}  // namespace

FilteredProfile gaussian_filter(const std::vector<double>& z_mm, double dx_mm, double cutoff_mm,
                                FilterEnds ends) {
  check_profile(z_mm, dx_mm, "Gaussian filter");
  if (!(std::isfinite(cutoff_mm) && cutoff_mm >= 2 * dx_mm)) {
    throw InputError(fmt::format(
        "Gaussian filter: the cut-off must be a finite number of at least two sample spacings "
        "({} mm), got {} mm",
        2 * dx_mm, cutoff_mm));
  }
  const std::size_t n = z_mm.size();
  if (n == 0) throw InputError("Gaussian filter: the profile is empty");
  // The weights before anything else is allocated: too many of them is an error of its own.
  const std::size_t full_half = kernel_half(dx_mm, cutoff_mm);
  if (ends == FilterEnds::discard && n < 2 * full_half + 1) {
    throw InputError(fmt::format(
        "Gaussian filter: {:.6g} mm of profile is shorter than two cut-offs ({:.6g} mm) and "
        "a sample: nothing is left after the run-in and run-out; give a longer profile, a "
        "shorter cut-off or ends = normalize",
        static_cast<double>(n - 1) * dx_mm, 2 * cutoff_mm));
  }
  const std::vector<double> w =
      gaussian_weights(dx_mm, cutoff_mm, ends == FilterEnds::discard ? full_half : n - 1);
  const std::size_t half = w.size() / 2;
  FilteredProfile out;
  if (ends == FilterEnds::discard) {
    out.first = half;
    out.mean_mm.resize(n - 2 * half);
    correlate(w, z_mm.data(), out.mean_mm.data(), n - 2 * half);
  } else {
    out.mean_mm.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k0 = i < half ? half - i : 0;
      const std::size_t k1 = std::min(w.size(), n + half - i);  // exclusive
      double m = 0, ws = 0;
      for (std::size_t k = k0; k < k1; ++k) {
        m += w[k] * z_mm[i + k - half];
        ws += w[k];
      }
      out.mean_mm[i] = m / ws;
    }
  }
  out.residual_mm.resize(out.mean_mm.size());
  for (std::size_t i = 0; i < out.mean_mm.size(); ++i) {
    out.residual_mm[i] = z_mm[out.first + i] - out.mean_mm[i];
  }
  return out;
}

FilteredProfile robust_gaussian_filter(const std::vector<double>& z_mm, double dx_mm,
                                       double cutoff_mm, FilterEnds ends) {
  FilteredProfile f = gaussian_filter(z_mm, dx_mm, cutoff_mm, ends);  // checks, and the start
  const std::size_t n = z_mm.size();
  const std::size_t half = ends == FilterEnds::discard
                               ? kernel_half(dx_mm, cutoff_mm)
                               : std::min(kernel_half(dx_mm, cutoff_mm), n - 1);
  const std::vector<double> w = gaussian_weights(dx_mm, cutoff_mm, half);
  const auto [lo, hi] = std::minmax_element(z_mm.begin(), z_mm.end());
  const double tolerance = 1e-9 * std::max(*hi - *lo, 1e-300);
  // The mean line at every sample the weights need (the outputs and, in discard mode, the
  // run-in and run-out around them): residuals over the whole profile.
  std::vector<double> mean(n), delta(n), r(n);
  auto full_mean = [&](const std::vector<double>* weights) {
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k0 = i < half ? half - i : 0;
      const std::size_t k1 = std::min(w.size(), n + half - i);
      double m = 0, ws = 0;
      for (std::size_t k = k0; k < k1; ++k) {
        const std::size_t j = i + k - half;
        const double wk = weights ? w[k] * (*weights)[j] : w[k];
        m += wk * z_mm[j];
        ws += wk;
      }
      // Every neighbour an outlier: the plain mean line there.
      if (ws > 0) {
        mean[i] = m / ws;
      } else {
        double mp = 0, wp = 0;
        for (std::size_t k = k0; k < k1; ++k) mp += w[k] * z_mm[i + k - half], wp += w[k];
        mean[i] = mp / wp;
      }
    }
  };
  full_mean(nullptr);
  for (int it = 0; it < 50; ++it) {
    for (std::size_t i = 0; i < n; ++i) r[i] = std::abs(z_mm[i] - mean[i]);
    std::vector<double> sorted = r;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(n / 2),
                     sorted.end());
    const double c = 4.4 * sorted[n / 2];
    if (!(c > 0)) break;  // half the profile on its mean line: nothing to weigh
    for (std::size_t i = 0; i < n; ++i) {
      const double u = (z_mm[i] - mean[i]) / c;
      delta[i] = std::abs(u) < 1 ? (1 - u * u) * (1 - u * u) : 0.0;
    }
    const std::vector<double> before = mean;
    full_mean(&delta);
    double moved = 0;
    for (std::size_t i = 0; i < n; ++i) moved = std::max(moved, std::abs(mean[i] - before[i]));
    if (moved < tolerance) break;
  }
  for (std::size_t i = 0; i < f.mean_mm.size(); ++i) {
    f.mean_mm[i] = mean[f.first + i];
    f.residual_mm[i] = z_mm[f.first + i] - f.mean_mm[i];
  }
  return f;
}

ProfileParameters profile_parameters(const std::vector<double>& z_mm, double dx_mm, int sections) {
  check_profile(z_mm, dx_mm, "profile parameters");
  if (sections < 1) {
    throw InputError(fmt::format("profile parameters: sections must be >= 1, got {}", sections));
  }
  const std::size_t n = z_mm.size();
  const auto ns = static_cast<std::size_t>(sections);
  if (n < 2 * ns) {
    throw InputError(fmt::format(
        "profile parameters: {} samples for {} sections; at least two per section", n, sections));
  }
  ProfileParameters p;
  p.sections = sections;
  p.evaluation_length_mm = static_cast<double>(n) * dx_mm;
  // Moments about the profile's mean line (z = 0 for a filtered profile; its mean otherwise).
  double mean = 0;
  for (const double z : z_mm) mean += z;
  mean /= static_cast<double>(n);
  double s1 = 0, s2 = 0, s3 = 0, s4 = 0;
  for (const double v : z_mm) {
    const double z = v - mean;
    s1 += std::abs(z), s2 += z * z, s3 += z * z * z, s4 += z * z * z * z;
  }
  const double dn = static_cast<double>(n);
  p.ra_mm = s1 / dn;
  p.rq_mm = std::sqrt(s2 / dn);
  p.rsk = p.rq_mm > 0 ? s3 / dn / (p.rq_mm * p.rq_mm * p.rq_mm) : 0.0;
  p.rku = p.rq_mm > 0 ? s4 / dn / (p.rq_mm * p.rq_mm * p.rq_mm * p.rq_mm) : 0.0;
  // Section-wise peak height and valley depth: sections of n / sections samples (the last
  // takes the remainder).
  double hi_all = -std::numeric_limits<double>::infinity(), lo_all = -hi_all;
  for (std::size_t k = 0; k < ns; ++k) {
    const std::size_t a = k * n / ns, b = (k + 1) * n / ns;
    const auto [lo, hi] = std::minmax_element(z_mm.begin() + static_cast<std::ptrdiff_t>(a),
                                              z_mm.begin() + static_cast<std::ptrdiff_t>(b));
    p.rp_mm += (*hi - mean) / static_cast<double>(ns);
    p.rv_mm += (mean - *lo) / static_cast<double>(ns);
    hi_all = std::max(hi_all, *hi), lo_all = std::min(lo_all, *lo);
  }
  p.rz_mm = p.rp_mm + p.rv_mm;
  p.rt_mm = hi_all - lo_all;
  // Profile elements: the stretches between crossings of the mean line, each a peak (above)
  // or a valley (below); one lower than 10 % of Rz or narrower than 1 % of the sampling
  // length belongs to its neighbours (they merge over it). An element is a peak and the valley
  // after it (or a valley and the peak after it); the stretches before the first crossing and
  // after the last are incomplete and not counted.
  struct Stretch {
    bool above;
    double width_mm, height_mm;
  };
  std::vector<double> cross;  // x of each crossing, mm
  std::vector<Stretch> st;
  for (std::size_t i = 1; i < n; ++i) {
    const double a = z_mm[i - 1] - mean, b = z_mm[i] - mean;
    if ((a < 0) != (b < 0)) cross.push_back((static_cast<double>(i - 1) + a / (a - b)) * dx_mm);
  }
  for (std::size_t c = 0; c + 1 < cross.size(); ++c) {
    const auto i0 = static_cast<std::size_t>(std::ceil(cross[c] / dx_mm));
    const auto i1 = std::min(n - 1, static_cast<std::size_t>(std::floor(cross[c + 1] / dx_mm)));
    const bool above = z_mm[std::min(i0, n - 1)] - mean >= 0;
    double h = 0;
    for (std::size_t i = i0; i <= i1; ++i) h = std::max(h, std::abs(z_mm[i] - mean));
    st.push_back({above, cross[c + 1] - cross[c], h});
  }
  const double min_h = 0.1 * p.rz_mm, min_w = 0.01 * p.evaluation_length_mm / sections;
  // One pass, left to right: everything already kept is large enough, so a small stretch
  // merges into the kept one before it (the three become one large stretch: it holds that
  // one) with the next; a small first stretch merges with the next into a stretch of that
  // one's sign, which is then judged in turn; a lone small stretch leaves nothing.
  auto small = [&](const Stretch& x) { return x.height_mm < min_h || x.width_mm < min_w; };
  std::vector<Stretch> kept;
  kept.reserve(st.size());
  std::optional<Stretch> carry;
  for (std::size_t i = 0;;) {
    Stretch cur;
    if (carry) {
      cur = *carry;
      carry.reset();
    } else if (i < st.size()) {
      cur = st[i++];
    } else {
      break;
    }
    if (!small(cur)) {
      kept.push_back(cur);
    } else if (!kept.empty()) {
      Stretch& a = kept.back();
      a.width_mm += cur.width_mm;
      if (i < st.size()) {
        a.width_mm += st[i].width_mm;
        a.height_mm = std::max(a.height_mm, st[i].height_mm);
        ++i;
      }
    } else if (i < st.size()) {
      carry = Stretch{st[i].above, cur.width_mm + st[i].width_mm, st[i].height_mm};
      ++i;
    }
  }
  st = std::move(kept);
  double widths = 0;
  for (std::size_t j = 0; j + 1 < st.size(); j += 2) {
    widths += st[j].width_mm + st[j + 1].width_mm;
    ++p.elements;
  }
  p.rsm_mm = p.elements > 0 ? widths / p.elements : 0.0;
  return p;
}

double default_cutoff_mm(double ra_mm) {
  const double ra_um = 1000.0 * ra_mm;
  if (ra_um <= 0.02) return 0.08;
  if (ra_um <= 0.1) return 0.25;
  if (ra_um <= 2) return 0.8;
  if (ra_um <= 10) return 2.5;
  return 8.0;
}

namespace {

// The roughness of the R profile `r` and the waviness of the W profile `w` (the mean line),
// `sections` sampling lengths of cut-off `lc`, the first sample `start` samples along the input.
ProfileTexture texture_of(std::vector<double> r, std::vector<double> w, double dx, double lc,
                          std::size_t sections, std::size_t start) {
  ProfileTexture t;
  t.cutoff_mm = lc;
  t.profile_dx_mm = dx;
  t.profile_start_mm = static_cast<double>(start) * dx;
  t.roughness = profile_parameters(r, dx, static_cast<int>(sections));
  double mean = 0;
  for (const double v : w) mean += v;
  mean /= static_cast<double>(w.size());
  for (const double v : w) t.wa_mm += std::abs(v - mean) / static_cast<double>(w.size());
  const auto [lo, hi] = std::minmax_element(w.begin(), w.end());
  t.wt_mm = *hi - *lo;
  t.roughness_profile_mm = std::move(r);
  t.waviness_profile_mm = std::move(w);
  return t;
}

// The texture with the given cut-off, or the ISO 21920-3 default found by iteration;
// `evaluate` gives the texture at a cut-off.
template <class Evaluate>
ProfileTexture choose_and_evaluate(std::optional<double> cutoff, const Evaluate& evaluate) {
  if (cutoff) {
    ProfileTexture t = evaluate(*cutoff);
    t.cutoff_source = "given";
    return t;
  }
  // From 0.8 mm along the table; where Ra's cut-off does not fit the profile (fewer than two
  // samples a cut-off, less than three cut-offs of profile), the series' cut-off nearest to it
  // that fits is taken, and the note says why.
  double lc = 0.8;
  std::optional<ProfileTexture> t;
  try {
    t = evaluate(lc);
  } catch (const InputError& e) {
    // Where the table starts does not fit a short profile: the series' nearest shorter
    // cut-off that does, else the error of the start (a profile too coarse for 0.8 mm is
    // refused: a longer cut-off would rest on a handful of samples).
    for (const double c : {0.25, 0.08}) {
      try {
        t = evaluate(c);
      } catch (const InputError&) {
        continue;
      }
      t->cutoff_source = fmt::format(
          "the nearest ISO 21920-3 cut-off this profile admits: 0.8 mm, where the default's "
          "table starts, does not fit it ({})",
          e.what());
      return *t;
    }
    throw;
  }
  for (int k = 0; k < 4; ++k) {
    const double next = default_cutoff_mm(t->roughness.ra_mm);
    if (next == lc) {
      t->cutoff_source = "ISO 21920-3 default from Ra";
      return *t;
    }
    try {
      t = evaluate(next);
      lc = next;
    } catch (const InputError& e) {
      // The series' values from `next` towards `lc` (exclusive): the first that fits.
      std::vector<double> between;
      for (const double c : {0.08, 0.25, 0.8, 2.5, 8.0}) {
        if ((c > next && c < lc) || (c < next && c > lc)) between.push_back(c);
      }
      if (next > lc) std::reverse(between.begin(), between.end());
      for (const double c : between) {
        try {
          t = evaluate(c);
          lc = c;
          break;
        } catch (const InputError&) {
        }
      }
      t->cutoff_source = fmt::format(
          "the nearest ISO 21920-3 cut-off this profile admits: the default from Ra, {:g} mm, "
          "does not fit it ({})",
          next, e.what());
      return *t;
    }
  }
  t->cutoff_source = "ISO 21920-3 default from Ra (Ra lies at a boundary of its table)";
  return *t;
}

// A cut-off the sampling resolves (the default one too: a coarse profile may not resolve it).
void check_resolved(double lc, double dx_mm) {
  if (!(lc >= 2 * dx_mm)) {
    throw InputError(fmt::format(
        "profile texture: the {:g} mm cut-off is shorter than two sample spacings ({:g} mm): "
        "the profile is sampled too coarsely for it; give a cut-off of at least {:g} mm",
        lc, 2 * dx_mm, 2 * dx_mm));
  }
}

void check_cutoff(std::optional<double> cutoff_mm, double dx_mm) {
  if (cutoff_mm && !(std::isfinite(*cutoff_mm) && *cutoff_mm >= 2 * dx_mm && *cutoff_mm <= 1e3)) {
    throw InputError(fmt::format(
        "profile texture: the cut-off must be between two sample spacings ({:g} mm) and 1000 "
        "mm, got {}",
        2 * dx_mm, *cutoff_mm));
  }
}

}  // namespace

ProfileTexture periodic_profile_texture(const std::vector<double>& period_z_mm, double dx_mm,
                                        std::optional<double> cutoff_mm) {
  check_profile(period_z_mm, dx_mm, "profile texture");
  check_cutoff(cutoff_mm, dx_mm);
  if (period_z_mm.size() < 2) throw InputError("profile texture: a period of fewer than 2 samples");
  const std::vector<double>& z = period_z_mm;
  const std::size_t n = z.size();
  return choose_and_evaluate(cutoff_mm, [&](double lc) {
    // The filter of the endless repetition is periodic: its mean line once over the period
    // (the weights wrapped around it), then the five sampling lengths read off the repetition
    // from where a run-in of one cut-off would have left it.
    check_resolved(lc, dx_mm);
    const double samples = 5 * std::round(lc / dx_mm);
    if (!(samples <= 5e7)) {
      throw InputError(fmt::format(
          "profile texture: {:g} mm cut-offs at {:g} mm spacing need {:.3g} samples (limit "
          "5e7)",
          lc, dx_mm, samples));
    }
    const std::vector<double> w = gaussian_weights(dx_mm, lc);
    const std::size_t half = w.size() / 2, per = static_cast<std::size_t>(std::llround(lc / dx_mm));
    // The period unrolled over the weights' reach: zz[i] = z[(i - half) mod n].
    const std::size_t shift = n - half % n;
    std::vector<double> zz(n + 2 * half);
    for (std::size_t i = 0; i < zz.size(); ++i) zz[i] = z[(i + shift) % n];
    std::vector<double> mean(n);
    correlate(w, zz.data(), mean.data(), n);
    std::vector<double> r(5 * per), wl(5 * per);
    for (std::size_t i = 0; i < r.size(); ++i) {
      const std::size_t j = (half + i) % n;
      r[i] = z[j] - mean[j];
      wl[i] = mean[j];
    }
    return texture_of(std::move(r), std::move(wl), dx_mm, lc, 5, half);
  });
}

ProfileTexture profile_texture(const std::vector<double>& raw_z_mm, double dx_mm,
                               std::optional<double> cutoff_mm, const ProfileFilterOptions& o) {
  check_profile(raw_z_mm, dx_mm, "profile texture");
  check_cutoff(cutoff_mm, dx_mm);
  // The primary profile: the lambda_s filter's mean line (renormalised at the ends: the
  // run-in and run-out the lambda_c filter drops cover them).
  std::vector<double> primary;
  if (o.lambda_s_mm) {
    const double ls = *o.lambda_s_mm;
    if (!(std::isfinite(ls) && ls >= 2 * dx_mm && (!cutoff_mm || ls < *cutoff_mm))) {
      throw InputError(fmt::format(
          "profile texture: {} must be at least two sample spacings ({:g} mm) and shorter "
          "than {}, got {} mm",
          option_name("lambda_s_mm"), 2 * dx_mm, option_name("lambda_c_mm"), ls));
    }
    primary = gaussian_filter(raw_z_mm, dx_mm, ls, FilterEnds::normalize).mean_mm;
  }
  const std::vector<double>& z_mm = o.lambda_s_mm ? primary : raw_z_mm;
  ProfileTexture t = choose_and_evaluate(cutoff_mm, [&](double lc) {
    // At most a run-in, five cut-offs and a run-out of the trace (ISO 21920-3's traverse);
    // what lies between the run-in and run-out, in sampling lengths of one cut-off.
    check_resolved(lc, dx_mm);
    const std::size_t half = kernel_half(dx_mm, lc);
    const auto per = static_cast<std::size_t>(std::llround(lc / dx_mm));
    const std::size_t n = std::min(z_mm.size(), 2 * half + 5 * per + 1);
    const std::size_t sections = n > 2 * half ? std::min<std::size_t>(5, (n - 2 * half) / per) : 0;
    if (sections < 1) {
      throw InputError(fmt::format(
          "profile texture: {:.4g} mm of profile holds less than three cut-offs of {:g} mm "
          "(run-in, one sampling length, run-out); give a longer profile or a shorter {}",
          static_cast<double>(z_mm.size()) * dx_mm, lc, option_name("lambda_c_mm")));
    }
    if (o.lambda_s_mm && *o.lambda_s_mm >= lc) {
      throw InputError(
          fmt::format("profile texture: lambda_s ({:g} mm) must be shorter than lambda_c ({:g} mm)",
                      *o.lambda_s_mm, lc));
    }
    const std::vector<double> part(z_mm.begin(), z_mm.begin() + static_cast<std::ptrdiff_t>(n));
    const FilteredProfile f = o.robust
                                  ? robust_gaussian_filter(part, dx_mm, lc, FilterEnds::discard)
                                  : gaussian_filter(part, dx_mm, lc, FilterEnds::discard);
    const auto len = static_cast<std::ptrdiff_t>(sections * per);
    return texture_of(std::vector<double>(f.residual_mm.begin(), f.residual_mm.begin() + len),
                      std::vector<double>(f.mean_mm.begin(), f.mean_mm.begin() + len), dx_mm, lc,
                      sections, f.first);
  });
  t.lambda_s_mm = o.lambda_s_mm.value_or(0.0);
  t.robust = o.robust;
  return t;
}

namespace {

// The spacing of equally spaced positions (to 1e-6 of a step), or InputError naming the line.
double equal_spacing(const std::vector<double>& x, const std::vector<std::size_t>& line,
                     std::string_view source, const char* what) {
  if (x.size() < 2) {
    throw InputError(fmt::format("{}: {} holds fewer than 2 points", source, what));
  }
  const double dx = (x.back() - x.front()) / static_cast<double>(x.size() - 1);
  if (!(dx > 0)) {
    throw InputError(fmt::format("{}: {} must increase along the profile", source, what));
  }
  const double first = x[1] - x[0];
  for (std::size_t i = 1; i < x.size(); ++i) {
    if (std::abs(x[i] - x[i - 1] - first) > 1e-6 * dx) {
      throw InputError(fmt::format(
          "{}:{}: {} must step equally ({:g} mm from the first point on), but steps {:g} mm here",
          source, line[i], what, first, x[i] - x[i - 1]));
    }
  }
  return dx;
}

}  // namespace

MeasuredProfile read_profile_csv(std::string_view text, std::string_view source,
                                 const std::string& x_column, const std::string& z_column,
                                 double z_to_mm) {
  CsvOptions o;
  o.detect_separator = true;
  if (!x_column.empty() || !z_column.empty()) {
    if (x_column.empty() || z_column.empty()) {
      throw InputError(fmt::format("{}: name both the x and the z column", source));
    }
    o.columns = {x_column, z_column};
  }
  const CsvTable t = parse_csv(text, source, o);
  MeasuredProfile p;
  std::vector<double> x;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (t.rows[r].size() < 2) {
      throw InputError(fmt::format("{}:{}: a profile row needs x and z", source, t.line_of_row[r]));
    }
    x.push_back(t.rows[r][0]);
    p.z_mm.push_back(t.rows[r][1] * z_to_mm);
  }
  p.dx_mm = equal_spacing(x, t.line_of_row, source, "x");
  p.description = fmt::format("profile of {} points every {:g} mm", x.size(), p.dx_mm);
  return p;
}

MeasuredProfile read_wall_profile_csv(std::string_view text, std::string_view source, bool left,
                                      std::optional<double> z_mm, bool machined_only) {
  CsvOptions o;
  o.columns = {"y_mm", "z_mm", left ? "left_x_mm" : "right_x_mm"};
  const CsvTable t = parse_csv(text, source, o);
  std::vector<double> levels;
  for (const auto& row : t.rows) levels.push_back(row[1]);
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  if (levels.empty()) throw InputError(fmt::format("{}: no wall points", source));
  double level = levels[levels.size() / 2];
  if (z_mm) {
    level = *std::min_element(levels.begin(), levels.end(), [&](double a, double b) {
      return std::abs(a - *z_mm) < std::abs(b - *z_mm);
    });
  }
  std::vector<std::pair<double, double>> pts;  // (y, height)
  std::vector<std::size_t> lines;
  for (std::size_t r = 0; r < t.rows.size(); ++r) {
    if (t.rows[r][1] != level) continue;
    pts.emplace_back(t.rows[r][0], left ? t.rows[r][2] : -t.rows[r][2]);
    lines.push_back(t.line_of_row[r]);
  }
  std::vector<std::size_t> order(pts.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](auto a, auto b) { return pts[a].first < pts[b].first; });
  std::vector<double> y;
  std::vector<std::size_t> line;
  MeasuredProfile p;
  for (const std::size_t i : order) {
    y.push_back(pts[i].first);
    line.push_back(lines[i]);
    p.z_mm.push_back(pts[i].second);
  }
  p.dx_mm = equal_spacing(y, line, source, fmt::format("y at z = {:g} mm", level).c_str());
  std::string front;
  if (machined_only && !y.empty()) {
    // Heights are material side up: the wall is the deepest, -|x| of the wall.
    const double half_width = -*std::min_element(p.z_mm.begin(), p.z_mm.end());
    const double y_cut = y.back() - half_width;
    const auto keep =
        static_cast<std::size_t>(std::upper_bound(y.begin(), y.end(), y_cut) - y.begin());
    if (keep < 3) {
      throw InputError(fmt::format(
          "{}: the {} wall at z = {:g} mm is all front arc (y {:g} to {:g} mm, the wall {:g} mm "
          "from the centre line): the simulation's window ended before a wall was finished; "
          "simulate more cycles",
          source, left ? "left" : "right", level, y.front(), y.back(), half_width));
    }
    if (keep < y.size()) {
      front = fmt::format("; the front arc, y {:g} to {:g} mm, left out", y[keep], y.back());
      y.resize(keep);
      p.z_mm.resize(keep);
    }
  }
  p.description = fmt::format("{} wall at z = {:g} mm, y {:g} to {:g} mm ({} points{})",
                              left ? "left" : "right", level, y.front(), y.back(), y.size(), front);
  return p;
}

MaterialRatioCurve material_ratio_curve(const std::vector<double>& z_mm, int points) {
  check_profile(z_mm, 1.0, "material ratio curve");
  if (z_mm.empty() || points < 2) {
    throw InputError("material ratio curve: needs a profile and at least 2 heights");
  }
  std::vector<double> sorted = z_mm;
  std::sort(sorted.begin(), sorted.end());
  const double top = sorted.back(), bottom = sorted.front();
  MaterialRatioCurve c;
  for (int k = 0; k < points; ++k) {
    const double h = top - (top - bottom) * k / (points - 1);
    // Samples at or above h: those from the first not below it.
    const auto at = std::lower_bound(sorted.begin(), sorted.end(), h);
    c.c_mm.push_back(h);
    c.ratio_percent.push_back(100.0 * static_cast<double>(sorted.end() - at) /
                              static_cast<double>(sorted.size()));
  }
  return c;
}

}  // namespace trochomill
