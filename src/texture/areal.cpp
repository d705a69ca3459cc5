// Areal surface texture: the ISO 16610-61 Gaussian filter (separable, FFT convolution with
// FFTW), the F-operator (least-squares plane or polynomial) and the ISO 25178-2 field
// parameters (texture.hpp; docs/models.md section "Surface texture").
//
// Determinism: every line (row or column) is filtered by the same FFTW plan (FFTW_ESTIMATE,
// made once per size) on its own buffer, so a line's result does not depend on which thread
// ran it or on the others; sums over the map run in one fixed order.
#include <fftw3.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <numbers>

#include "texture/gaussian.hpp"
#include "trochomill/error.hpp"
#include "trochomill/texture.hpp"

namespace trochomill {

namespace {

// FFTW's planner is not thread-safe (its execute functions are).
std::mutex& planner_mutex() {
  static std::mutex m;
  return m;
}

// The smallest n' >= n of the form 2^a 3^b 5^c 7^d (FFTW's fast sizes).
std::size_t fast_fft_size(std::size_t n) {
  for (std::size_t m = std::max<std::size_t>(n, 1);; ++m) {
    std::size_t r = m;
    for (const std::size_t p : {2, 3, 5, 7}) {
      while (r % p == 0) r /= p;
    }
    if (r == 1) return m;
  }
}

// FFTW's double and single precision interfaces under one name.
template <class Real>
struct Fftw;
template <>
struct Fftw<double> {
  using complex = fftw_complex;
  using plan = fftw_plan;
  static void* allocate(std::size_t bytes) { return fftw_malloc(bytes); }
  static void release(void* p) { fftw_free(p); }
  static plan r2c(int n, double* in, complex* out) {
    return fftw_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
  }
  static plan c2r(int n, complex* in, double* out) {
    return fftw_plan_dft_c2r_1d(n, in, out, FFTW_ESTIMATE);
  }
  static plan dft(int n, complex* in, complex* out, int sign) {
    return fftw_plan_dft_1d(n, in, out, sign, FFTW_ESTIMATE);
  }
  static void destroy(plan p) { fftw_destroy_plan(p); }
  static void run(plan p, double* in, complex* out) { fftw_execute_dft_r2c(p, in, out); }
  static void run(plan p, complex* in, double* out) { fftw_execute_dft_c2r(p, in, out); }
  static void run(plan p, complex* in, complex* out) { fftw_execute_dft(p, in, out); }
};
template <>
struct Fftw<float> {
  using complex = fftwf_complex;
  using plan = fftwf_plan;
  static void* allocate(std::size_t bytes) { return fftwf_malloc(bytes); }
  static void release(void* p) { fftwf_free(p); }
  static plan r2c(int n, float* in, complex* out) {
    return fftwf_plan_dft_r2c_1d(n, in, out, FFTW_ESTIMATE);
  }
  static plan c2r(int n, complex* in, float* out) {
    return fftwf_plan_dft_c2r_1d(n, in, out, FFTW_ESTIMATE);
  }
  static plan dft(int n, complex* in, complex* out, int sign) {
    return fftwf_plan_dft_1d(n, in, out, sign, FFTW_ESTIMATE);
  }
  static void destroy(plan p) { fftwf_destroy_plan(p); }
  static void run(plan p, float* in, complex* out) { fftwf_execute_dft_r2c(p, in, out); }
  static void run(plan p, complex* in, float* out) { fftwf_execute_dft_c2r(p, in, out); }
  static void run(plan p, complex* in, complex* out) { fftwf_execute_dft(p, in, out); }
};

template <class Real>
struct FftwFree {
  void operator()(void* p) const { Fftw<Real>::release(p); }
};
template <class T, class Real = double>
using FftwBuffer = std::unique_ptr<T[], FftwFree<Real>>;

template <class T, class Real = double>
FftwBuffer<T, Real> fftw_buffer(std::size_t n) {
  auto* p = static_cast<T*>(Fftw<Real>::allocate(sizeof(T) * std::max<std::size_t>(n, 1)));
  if (p == nullptr) throw std::bad_alloc();
  return FftwBuffer<T, Real>(p);
}

// One real-to-complex and its inverse plan of length n (FFTW_ESTIMATE: the same plan for the
// same size, whatever ran before).
template <class Real = double>
class RealPlans {
 public:
  using F = Fftw<Real>;
  using complex = typename F::complex;
  explicit RealPlans(std::size_t n) : n_(n) {
    auto in = fftw_buffer<Real, Real>(n);
    auto out = fftw_buffer<complex, Real>(n / 2 + 1);
    const std::lock_guard lock(planner_mutex());
    const int ni = static_cast<int>(n);
    forward_ = F::r2c(ni, in.get(), out.get());
    inverse_ = F::c2r(ni, out.get(), in.get());
    if (forward_ == nullptr || inverse_ == nullptr) throw Error("FFTW could not plan a transform");
  }
  RealPlans(const RealPlans&) = delete;
  RealPlans& operator=(const RealPlans&) = delete;
  ~RealPlans() {
    const std::lock_guard lock(planner_mutex());
    F::destroy(forward_);
    F::destroy(inverse_);
  }
  [[nodiscard]] std::size_t size() const { return n_; }
  void forward(Real* in, complex* out) const { F::run(forward_, in, out); }
  // Destroys `in` (FFTW's c2r does).
  void inverse(complex* in, Real* out) const { F::run(inverse_, in, out); }

 private:
  std::size_t n_;
  typename F::plan forward_ = nullptr, inverse_ = nullptr;
};

// A complex transform of length n, both directions.
template <class Real = double>
class ComplexPlans {
 public:
  using F = Fftw<Real>;
  using complex = typename F::complex;
  explicit ComplexPlans(std::size_t n) {
    auto a = fftw_buffer<complex, Real>(n);
    auto b = fftw_buffer<complex, Real>(n);
    const std::lock_guard lock(planner_mutex());
    const int ni = static_cast<int>(n);
    forward_ = F::dft(ni, a.get(), b.get(), FFTW_FORWARD);
    inverse_ = F::dft(ni, a.get(), b.get(), FFTW_BACKWARD);
    if (forward_ == nullptr || inverse_ == nullptr) throw Error("FFTW could not plan a transform");
  }
  ComplexPlans(const ComplexPlans&) = delete;
  ComplexPlans& operator=(const ComplexPlans&) = delete;
  ~ComplexPlans() {
    const std::lock_guard lock(planner_mutex());
    F::destroy(forward_);
    F::destroy(inverse_);
  }
  void forward(complex* in, complex* out) const { F::run(forward_, in, out); }
  void inverse(complex* in, complex* out) const { F::run(inverse_, in, out); }

 private:
  typename F::plan forward_ = nullptr, inverse_ = nullptr;
};

// Below this many weights a line is convolved directly (fewer operations than two FFTs).
constexpr std::size_t kDirectWeights = 48;

// The Gaussian mean line of lines of n samples: out[i] = sum_k w[k] z[i + k - h] over the
// samples on the line, divided by the sum of those weights (renormalised ends).
class LineFilter {
 public:
  LineFilter(std::size_t n, double spacing_mm, double cutoff_mm)
      : n_(n), w_(detail::gaussian_weights(spacing_mm, cutoff_mm, n - 1)) {
    half_ = w_.size() / 2;
    // The weights on the line at each output: a prefix-sum difference.
    std::vector<double> prefix(w_.size() + 1, 0.0);
    for (std::size_t k = 0; k < w_.size(); ++k) prefix[k + 1] = prefix[k] + w_[k];
    norm_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t k0 = i < half_ ? half_ - i : 0;
      const std::size_t k1 = std::min(w_.size(), n + half_ - i);
      norm_[i] = prefix[k1] - prefix[k0];
    }
    if (w_.size() > kDirectWeights) {
      // Linear convolution by a circular one: n + half zero-padded samples are enough (the
      // wrapped weights meet only padding at the outputs kept).
      plans_ = std::make_unique<RealPlans<>>(fast_fft_size(n + half_));
      const std::size_t m = plans_->size();
      auto kern = fftw_buffer<double>(m);
      std::fill(kern.get(), kern.get() + m, 0.0);
      for (std::size_t k = 0; k < w_.size(); ++k) kern[(k + m - half_) % m] = w_[k];
      kernel_.resize(m / 2 + 1);
      auto spec = fftw_buffer<fftw_complex>(m / 2 + 1);
      plans_->forward(kern.get(), spec.get());
      // The inverse transform is unnormalised: the 1/m goes into the kernel's spectrum.
      const double scale = 1.0 / static_cast<double>(m);
      for (std::size_t j = 0; j < kernel_.size(); ++j) kernel_[j] = spec[j][0] * scale;
    }
  }

  // Scratch buffers for one thread.
  struct Work {
    FftwBuffer<double> real;
    FftwBuffer<fftw_complex> spec;
  };
  [[nodiscard]] Work work() const {
    const std::size_t m = plans_ ? plans_->size() : n_;
    return {fftw_buffer<double>(m), fftw_buffer<fftw_complex>(m / 2 + 1)};
  }

  // Filters the line in[0..n) (read with `stride`) into out[0..n) (written with `stride`).
  // Filters the line in[0..n) into out[0..n) (they may be the same: the line is copied first).
  void run(const double* in, double* out, Work& work) const {
    double* r = work.real.get();
    std::copy(in, in + n_, r);
    if (!plans_) {
      // Term by term over the whole line (each output sums its weights in k order, as the
      // ends do): the inner loop runs along the line and vectorises.
      std::fill(out, out + n_, 0.0);
      for (std::size_t k = 0; k < w_.size(); ++k) {
        const double wk = w_[k];
        // outputs i with 0 <= i + k - half < n
        const std::size_t i0 = k < half_ ? half_ - k : 0;
        const std::size_t i1 = std::min(n_, n_ + half_ - k);
        const double* src = r + (i0 + k - half_);
        for (std::size_t i = i0; i < i1; ++i) out[i] += wk * src[i - i0];
      }
      for (std::size_t i = 0; i < n_; ++i) out[i] /= norm_[i];
      return;
    }
    const std::size_t m = plans_->size();
    std::fill(r + n_, r + m, 0.0);
    plans_->forward(r, work.spec.get());
    // The kernel is even about its centre: its spectrum is real (to rounding).
    for (std::size_t j = 0; j < kernel_.size(); ++j) {
      work.spec[j][0] *= kernel_[j];
      work.spec[j][1] *= kernel_[j];
    }
    plans_->inverse(work.spec.get(), r);
    for (std::size_t i = 0; i < n_; ++i) out[i] = r[i] / norm_[i];
  }

 private:
  std::size_t n_, half_ = 0;
  std::vector<double> w_, norm_;
  std::unique_ptr<RealPlans<>> plans_;
  std::vector<double> kernel_;
};

void check_nesting_index(const HeightMap& map, double cutoff_mm, const char* what) {
  const double finest = std::max(map.dx_mm, map.dy_mm);
  if (!(std::isfinite(cutoff_mm) && cutoff_mm >= 2 * finest)) {
    throw InputError(fmt::format(
        "{}: the nesting index must be a finite number of at least two sample spacings ({:g} "
        "mm), got {} mm",
        what, 2 * finest, cutoff_mm));
  }
  (void)detail::kernel_half(map.dx_mm, cutoff_mm);
  (void)detail::kernel_half(map.dy_mm, cutoff_mm);
}

// Columns are filtered in blocks of this many (their samples of a row lie side by side).
constexpr std::size_t kColumnBlock = 8;

}  // namespace

void check_height_map(const HeightMap& map, std::string_view what) {
  if (map.nx < 2 || map.ny < 2) {
    throw InputError(fmt::format("{}: a height map needs at least 2 x 2 points, got {} x {}", what,
                                 map.nx, map.ny));
  }
  for (const auto& [v, name] : {std::pair{map.dx_mm, "x"}, std::pair{map.dy_mm, "y"}}) {
    if (!(std::isfinite(v) && v > 0 && v < 1e6)) {
      throw InputError(fmt::format(
          "{}: the {} spacing must be a finite number in (0, 1e6) mm, got {}", what, name, v));
    }
  }
  if (map.z_mm.size() != map.nx * map.ny) {
    throw InputError(
        fmt::format("{}: {} heights for {} x {} points", what, map.z_mm.size(), map.nx, map.ny));
  }
  for (std::size_t i = 0; i < map.z_mm.size(); ++i) {
    if (!std::isfinite(map.z_mm[i])) {
      throw InputError(fmt::format("{}: the height at column {}, row {} is not a finite number",
                                   what, i % map.nx, i / map.nx));
    }
  }
}

namespace {

// The areal Gaussian mean surface of `map` (checked) into out[0..nx ny): the rows into `out`,
// then the columns of `out` in place.
// With `residual`, the map less its mean surface instead (the last pass writes it).
void filter_into(const HeightMap& map, double cutoff_mm, double* out, bool residual = false) {
  const std::size_t nx = map.nx, ny = map.ny;
  {
    const LineFilter f(nx, map.dx_mm, cutoff_mm);
    tbb::enumerable_thread_specific<LineFilter::Work> work([&] { return f.work(); });
    tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t r) {
      f.run(map.z_mm.data() + r * nx, out + r * nx, work.local());
    });
  }
  const double* tmp = out;
  {  // then each column, in blocks gathered row by row (their samples lie side by side); a
     // block is read whole before it is written back
    const LineFilter f(ny, map.dy_mm, cutoff_mm);
    struct ColumnWork {
      LineFilter::Work line;
      std::vector<double> in, out;
    };
    tbb::enumerable_thread_specific<ColumnWork> work([&] {
      return ColumnWork{f.work(), std::vector<double>(ny * kColumnBlock),
                        std::vector<double>(ny * kColumnBlock)};
    });
    const std::size_t blocks = (nx + kColumnBlock - 1) / kColumnBlock;
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
      ColumnWork& w = work.local();
      const std::size_t c0 = b * kColumnBlock, nc = std::min(kColumnBlock, nx - c0);
      for (std::size_t r = 0; r < ny; ++r) {
        for (std::size_t c = 0; c < nc; ++c) w.in[c * ny + r] = tmp[r * nx + c0 + c];
      }
      for (std::size_t c = 0; c < nc; ++c) {
        f.run(w.in.data() + c * ny, w.out.data() + c * ny, w.line);
      }
      for (std::size_t r = 0; r < ny; ++r) {
        double* o = out + r * nx + c0;
        if (residual) {
          const double* z = map.z_mm.data() + r * nx + c0;
          for (std::size_t c = 0; c < nc; ++c) o[c] = z[c] - w.out[c * ny + r];
        } else {
          for (std::size_t c = 0; c < nc; ++c) o[c] = w.out[c * ny + r];
        }
      }
    });
  }
}

// Asks for transparent huge pages on a large buffer about to be first touched: on a
// virtual machine a 4 KB page fault costs more than the filter's arithmetic on the page.
void prefer_huge_pages(void* p, std::size_t bytes) {
  constexpr std::uintptr_t kHuge = 2u << 20;
  const auto a = (reinterpret_cast<std::uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const auto b = (reinterpret_cast<std::uintptr_t>(p) + bytes) & ~(kHuge - 1);
  if (b > a) (void)::madvise(reinterpret_cast<void*>(a), b - a, MADV_HUGEPAGE);
}

// A vector of n doubles, zeroed, on huge pages where the system gives them.
void zeroed(std::vector<double>& v, std::size_t n) {
  v.clear();
  v.reserve(n);
  prefer_huge_pages(v.data(), n * sizeof(double));
  v.resize(n);
}

HeightMap same_grid(const HeightMap& map, std::string description) {
  HeightMap out;
  out.nx = map.nx, out.ny = map.ny, out.dx_mm = map.dx_mm, out.dy_mm = map.dy_mm;
  out.x0_mm = map.x0_mm, out.y0_mm = map.y0_mm;
  out.description = std::move(description);
  return out;
}

// The public functions check their input; areal_texture checks the map once and calls
// these (a derived surface of a finite map is finite).
HeightMap mean_surface(const HeightMap& map, double cutoff_mm, bool residual = false) {
  HeightMap out = same_grid(
      map, map.description +
               (residual ? fmt::format(", less its Gaussian mean surface {:g} mm", cutoff_mm)
                         : fmt::format(", Gaussian mean surface {:g} mm", cutoff_mm)));
  zeroed(out.z_mm, map.z_mm.size());
  filter_into(map, cutoff_mm, out.z_mm.data(), residual);
  return out;
}

}  // namespace

// Unchecked cores of remove_form and areal_parameters (internal; defined below).
HeightMap form_removed(HeightMap map, FormRemoval form, int degree);
// `scale_mm`: the size of the heights the surface was derived from (a filtered or form-removed
// surface's rounding errors are relative to those, not to what is left).
ArealParameters parameters_of(const HeightMap& s, bool autocorrelation_lengths,
                              double scale_mm = 0);

HeightMap gaussian_filter_areal(const HeightMap& map, double cutoff_mm) {
  check_height_map(map, "areal Gaussian filter");
  check_nesting_index(map, cutoff_mm, "areal Gaussian filter");
  return mean_surface(map, cutoff_mm);
}

const char* form_removal_name(FormRemoval form) {
  switch (form) {
    case FormRemoval::none:
      return "none";
    case FormRemoval::plane:
      return "plane";
    case FormRemoval::polynomial:
      return "polynomial";
  }
  return "?";
}

HeightMap remove_form(HeightMap map, FormRemoval form, int degree) {
  check_height_map(map, "form removal");
  return form_removed(std::move(map), form, degree);
}

HeightMap form_removed(HeightMap map, FormRemoval form, int degree) {
  if (form == FormRemoval::polynomial && (degree < 1 || degree > 6)) {
    throw InputError(
        fmt::format("form removal: the polynomial degree must be 1 to 6, got {}", degree));
  }
  const int d = form == FormRemoval::none ? 0 : form == FormRemoval::plane ? 1 : degree;
  const std::size_t nx = map.nx, ny = map.ny;
  // Legendre polynomials of u in [-1, 1] across each side: well conditioned at any degree here.
  auto legendre = [d](std::size_t n) {
    std::vector<double> p((static_cast<std::size_t>(d) + 1) * n);
    for (std::size_t i = 0; i < n; ++i) {
      const double u = 2.0 * static_cast<double>(i) / static_cast<double>(n - 1) - 1.0;
      p[i] = 1.0;
      if (d >= 1) p[n + i] = u;
      for (int k = 2; k <= d; ++k) {
        const auto kk = static_cast<std::size_t>(k);
        p[kk * n + i] =
            ((2.0 * k - 1) * u * p[(kk - 1) * n + i] - (k - 1.0) * p[(kk - 2) * n + i]) /
            static_cast<double>(k);
      }
    }
    return p;
  };
  const std::vector<double> px = legendre(nx), py = legendre(ny);
  // The terms P_i(u) P_j(v) with i + j <= d. On the full grid the normal equations separate:
  // sum P_i P_j' Q_k Q_l = (sum_x P_i P_i')(sum_y Q_k Q_l); the right side sums row moments.
  std::vector<std::pair<int, int>> terms;
  for (int t = 0; t <= d; ++t) {
    for (int j = 0; j <= t; ++j) terms.emplace_back(t - j, j);
  }
  const auto D = static_cast<std::size_t>(d) + 1;
  Eigen::MatrixXd gx(D, D), gy(D, D);
  for (std::size_t a = 0; a < D; ++a) {
    for (std::size_t b = 0; b < D; ++b) {
      double sx = 0, sy = 0;
      for (std::size_t i = 0; i < nx; ++i) sx += px[a * nx + i] * px[b * nx + i];
      for (std::size_t i = 0; i < ny; ++i) sy += py[a * ny + i] * py[b * ny + i];
      gx(a, b) = sx, gy(a, b) = sy;
    }
  }
  // moments(i, r) = sum over the row r of P_i(u) z; then the right side sums Q_j(v) over rows.
  Eigen::MatrixXd moments(D, ny);
  tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t r) {  // each its own: deterministic
    for (std::size_t a = 0; a < D; ++a) {
      double s = 0;
      for (std::size_t c = 0; c < nx; ++c) s += px[a * nx + c] * map.z_mm[r * nx + c];
      moments(a, r) = s;
    }
  });
  const auto T = terms.size();
  Eigen::MatrixXd normal(T, T);
  Eigen::VectorXd rhs(T);
  for (std::size_t p = 0; p < T; ++p) {
    const auto [i, j] = terms[p];
    for (std::size_t q = 0; q < T; ++q) {
      normal(p, q) = gx(i, terms[q].first) * gy(j, terms[q].second);
    }
    double s = 0;
    for (std::size_t r = 0; r < ny; ++r)
      s += moments(i, r) * py[static_cast<std::size_t>(j) * ny + r];
    rhs(p) = s;
  }
  const Eigen::VectorXd coef = normal.ldlt().solve(rhs);
  // The fit along each row: sum_j Q_j(v) sum_i c_ij P_i(u), the inner sums per row first.
  tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t r) {
    std::vector<double> cx(D, 0.0);  // the coefficient of P_i(u) on this row
    for (std::size_t p = 0; p < T; ++p) {
      const auto [i, j] = terms[p];
      cx[static_cast<std::size_t>(i)] +=
          coef(static_cast<Eigen::Index>(p)) * py[static_cast<std::size_t>(j) * ny + r];
    }
    double* z = map.z_mm.data() + r * nx;
    for (std::size_t c = 0; c < nx; ++c) {
      double f = 0;
      for (std::size_t i = 0; i < D; ++i) f += cx[i] * px[i * nx + c];
      z[c] -= f;
    }
  });
  return map;
}

namespace {

// The areal autocorrelation function for lags 0..lx along x and -ly..ly along y (samples),
// normalised by each lag's overlap (an unbiased estimate) and to 1 at zero lag:
// acf[(ty + ly) * (lx + 1) + tx]. By the map padded with zeros to at least (nx + lx) x
// (ny + ly): rows by real FFT, columns by complex FFT, |.|^2, and back.
std::vector<float> autocorrelation(const HeightMap& s, double mean, std::size_t lx,
                                   std::size_t ly) {
  const std::size_t nx = s.nx, ny = s.ny;
  const std::size_t px = fast_fft_size(nx + lx), py = fast_fft_size(ny + ly), hx = px / 2 + 1;
  // Single precision: the function's values (to 1e-6) place Sal far more finely than its
  // bilinear interpolation does, at half the memory and time of double.
  using C = fftwf_complex;
  const RealPlans<float> rows(px);
  const ComplexPlans<float> cols(py);
  const std::size_t wx = lx + 1, wy = 2 * ly + 1;
  // The row spectra [row][frequency along x], then in the same rows the columns' results at
  // the lags kept (ty = -ly..ly in rows 0..2ly); not initialised: every value read is written.
  auto spec = fftw_buffer<C, float>(std::max(ny, wy) * hx);
  prefer_huge_pages(spec.get(), std::max(ny, wy) * hx * sizeof(C));
  {
    struct Work {
      FftwBuffer<float, float> real;
      FftwBuffer<C, float> out;
    };
    tbb::enumerable_thread_specific<Work> work([&] {
      return Work{fftw_buffer<float, float>(px), fftw_buffer<C, float>(hx)};
    });
    tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t r) {
      Work& w = work.local();
      for (std::size_t c = 0; c < nx; ++c)
        w.real[c] = static_cast<float>(s.z_mm[r * nx + c] - mean);
      std::fill(w.real.get() + nx, w.real.get() + px, 0.0f);
      rows.forward(w.real.get(), w.out.get());
      std::memcpy(spec.get() + r * hx, w.out.get(), hx * sizeof(C));
    });
  }
  {  // frequency columns in blocks: forward, power, inverse (rows past ny are zero)
    struct Work {
      FftwBuffer<C, float> a, b;
    };
    tbb::enumerable_thread_specific<Work> work([&] {
      return Work{fftw_buffer<C, float>(py * kColumnBlock),
                  fftw_buffer<C, float>(py * kColumnBlock)};
    });
    const std::size_t blocks = (hx + kColumnBlock - 1) / kColumnBlock;
    tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t blk) {
      Work& w = work.local();
      const std::size_t j0 = blk * kColumnBlock, nj = std::min(kColumnBlock, hx - j0);
      for (std::size_t r = 0; r < py; ++r) {
        for (std::size_t j = 0; j < nj; ++j) {
          C& d = w.a[j * py + r];
          if (r < ny) {
            d[0] = spec[r * hx + j0 + j][0], d[1] = spec[r * hx + j0 + j][1];
          } else {
            d[0] = d[1] = 0;
          }
        }
      }
      for (std::size_t j = 0; j < nj; ++j) {
        C* a = w.a.get() + j * py;
        C* b = w.b.get() + j * py;
        cols.forward(a, b);
        for (std::size_t r = 0; r < py; ++r) {
          b[r][0] = b[r][0] * b[r][0] + b[r][1] * b[r][1];
          b[r][1] = 0;
        }
        cols.inverse(b, a);
      }
      for (std::size_t k = 0; k < wy; ++k) {
        const std::size_t r = k >= ly ? k - ly : py - (ly - k);
        for (std::size_t j = 0; j < nj; ++j) {
          spec[k * hx + j0 + j][0] = w.a[j * py + r][0];
          spec[k * hx + j0 + j][1] = w.a[j * py + r][1];
        }
      }
    });
  }
  std::vector<float> acf(wx * wy);
  {
    struct Work {
      FftwBuffer<C, float> in;
      FftwBuffer<float, float> out;
    };
    tbb::enumerable_thread_specific<Work> work([&] {
      return Work{fftw_buffer<C, float>(hx), fftw_buffer<float, float>(px)};
    });
    tbb::parallel_for(std::size_t{0}, wy, [&](std::size_t k) {
      Work& w = work.local();
      const auto ty = static_cast<std::ptrdiff_t>(k) - static_cast<std::ptrdiff_t>(ly);
      std::memcpy(w.in.get(), spec.get() + k * hx, hx * sizeof(C));
      rows.inverse(w.in.get(), w.out.get());
      const double oy = static_cast<double>(ny - static_cast<std::size_t>(std::abs(ty)));
      for (std::size_t tx = 0; tx < wx; ++tx) {
        acf[k * wx + tx] = static_cast<float>(w.out[tx] / (oy * static_cast<double>(nx - tx)));
      }
    });
  }
  const float zero = acf[ly * wx];
  for (float& v : acf) v /= zero;
  return acf;
}

}  // namespace

ArealParameters areal_parameters(const HeightMap& s, bool autocorrelation_lengths) {
  check_height_map(s, "areal parameters");
  return parameters_of(s, autocorrelation_lengths);
}

ArealParameters parameters_of(const HeightMap& s, bool autocorrelation_lengths, double scale_mm) {
  const std::size_t nx = s.nx, ny = s.ny, n = nx * ny;
  ArealParameters p;
  p.area_mm2 = static_cast<double>(nx - 1) * s.dx_mm * static_cast<double>(ny - 1) * s.dy_mm;
  // Sums row by row (in parallel), then over the rows in order: the same result for any
  // thread count.
  std::vector<double> row_sum(ny);
  tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t r) {
    double t = 0;
    for (std::size_t c = 0; c < nx; ++c) t += s.z_mm[r * nx + c];
    row_sum[r] = t;
  });
  double mean = 0;
  for (const double t : row_sum) mean += t;
  mean /= static_cast<double>(n);
  struct Row {
    double s1, s2, s3, s4, hi, lo, developed;
  };
  std::vector<Row> rows(ny);
  const double idx = 0.5 / s.dx_mm, idy = 0.5 / s.dy_mm;
  tbb::parallel_for(std::size_t{0}, ny, [&](std::size_t r) {
    Row q{0, 0, 0, 0, -INFINITY, INFINITY, 0};
    const double* z0 = s.z_mm.data() + r * nx;
    for (std::size_t c = 0; c < nx; ++c) {
      const double z = z0[c] - mean, z2 = z * z;
      q.s1 += std::abs(z), q.s2 += z2, q.s3 += z2 * z, q.s4 += z2 * z2;
      q.hi = std::max(q.hi, z), q.lo = std::min(q.lo, z);
    }
    // Sdr: each cell's slopes, the mean of its two edges in each direction.
    if (r + 1 < ny) {
      const double* z1 = z0 + nx;
      for (std::size_t c = 0; c + 1 < nx; ++c) {
        const double gx = ((z0[c + 1] - z0[c]) + (z1[c + 1] - z1[c])) * idx;
        const double gy = ((z1[c] - z0[c]) + (z1[c + 1] - z0[c + 1])) * idy;
        q.developed += std::sqrt(1.0 + gx * gx + gy * gy);
      }
    }
    rows[r] = q;
  });
  double s1 = 0, s2 = 0, s3 = 0, s4 = 0, hi = -INFINITY, lo = INFINITY, developed = 0;
  for (const Row& q : rows) {
    s1 += q.s1, s2 += q.s2, s3 += q.s3, s4 += q.s4, developed += q.developed;
    hi = std::max(hi, q.hi), lo = std::min(lo, q.lo);
  }
  const double dn = static_cast<double>(n);
  p.sa_mm = s1 / dn;
  p.sq_mm = std::sqrt(s2 / dn);
  // A surface flat to rounding (Sq within 1e-12 of its heights' size, or of the heights it
  // was derived from) has no shape: Ssk, Sku, Sal and Str stay 0 and empty rather than ratios
  // of rounding errors.
  const double size = std::max({std::abs(hi + mean), std::abs(lo + mean), scale_mm, 1e-300});
  const bool flat = p.sq_mm <= 1e-12 * size;
  p.flat = flat;
  p.ssk = flat ? 0.0 : s3 / dn / std::pow(p.sq_mm, 3);
  p.sku = flat ? 0.0 : s4 / dn / std::pow(p.sq_mm, 4);
  p.sp_mm = hi, p.sv_mm = -lo, p.sz_mm = hi - lo;
  p.sdr_percent = 100.0 * (developed / static_cast<double>((nx - 1) * (ny - 1)) - 1.0);
  if (!autocorrelation_lengths || flat) return p;

  const std::size_t lx = nx / 2, ly = ny / 2, wx = lx + 1;
  const std::vector<float> acf = autocorrelation(s, mean, lx, ly);
  auto at = [&](double tx, double ty) {  // bilinear, lags in samples; tx >= 0
    const double fx = std::floor(tx), fy = std::floor(ty);
    const auto i = static_cast<std::size_t>(fx);
    const auto k = static_cast<std::size_t>(fy + static_cast<double>(ly));
    const double ax = tx - fx, ay = ty - fy;
    const std::size_t i1 = std::min(i + 1, lx), k1 = std::min(k + 1, 2 * ly);
    const auto v = [&](std::size_t q) { return static_cast<double>(acf[q]); };
    return (1 - ay) * ((1 - ax) * v(k * wx + i) + ax * v(k * wx + i1)) +
           ay * ((1 - ax) * v(k1 * wx + i) + ax * v(k1 * wx + i1));
  };
  // Each direction in [0, 180) degrees (the function is even: t and -t agree), marched out in
  // steps of half the finer spacing to the first value under 0.2 (the interpolated function
  // is linear along a step's grid lines: it cannot dip under and back within one), refined by
  // bisection; directions run in parallel, each into its own slot (-1: no decay).
  constexpr double kThreshold = 0.2;
  constexpr int kDirections = 360;
  const double step = 0.5 * std::min(s.dx_mm, s.dy_mm);
  std::vector<double> decay(kDirections);
  tbb::parallel_for(0, kDirections, [&](int a) {
    const double th = a * std::numbers::pi / kDirections;
    double cx = std::cos(th), cy = std::sin(th);
    if (cx < 0) cx = -cx, cy = -cy;  // keep tx >= 0 (the function is even)
    auto value = [&](double r) { return at(r * cx / s.dx_mm, r * cy / s.dy_mm); };
    auto inside = [&](double r) {
      return r * cx / s.dx_mm <= static_cast<double>(lx) &&
             std::abs(r * cy / s.dy_mm) <= static_cast<double>(ly) - 1e-9;
    };
    double r0 = 0, r1 = step;
    bool found = false;
    while (inside(r1)) {
      if (value(r1) < kThreshold) {
        found = true;
        break;
      }
      r0 = r1, r1 += step;
    }
    if (!found) {
      decay[static_cast<std::size_t>(a)] = -1;
      return;
    }
    for (int it = 0; it < 40; ++it) {
      const double m = 0.5 * (r0 + r1);
      (value(m) < kThreshold ? r1 : r0) = m;
    }
    decay[static_cast<std::size_t>(a)] = 0.5 * (r0 + r1);
  });
  double shortest = INFINITY, longest = 0;
  bool all = true;
  for (const double r : decay) {
    if (r < 0) {
      all = false;
    } else {
      shortest = std::min(shortest, r), longest = std::max(longest, r);
    }
  }
  if (std::isfinite(shortest)) p.sal_mm = shortest;
  if (all && longest > 0) p.str = shortest / longest;
  return p;
}

ArealTexture areal_texture(const HeightMap& map, const ArealFilterOptions& o) {
  check_height_map(map, "areal texture");
  const double shorter = std::min(static_cast<double>(map.nx - 1) * map.dx_mm,
                                  static_cast<double>(map.ny - 1) * map.dy_mm);
  ArealTexture t;
  t.form = o.form;
  t.degree = o.form == FormRemoval::polynomial ? o.degree : o.form == FormRemoval::plane ? 1 : 0;
  if (o.s_mm) {
    check_nesting_index(map, *o.s_mm, "S-filter");
    t.s_mm = *o.s_mm;
  }
  // The S-filter keeps the long wavelengths (its mean surface); then the form goes.
  const HeightMap sf = o.s_mm ? form_removed(mean_surface(map, *o.s_mm), o.form, o.degree)
                              : form_removed(map, o.form, o.degree);
  double scale = 0;
  for (const double z : map.z_mm) scale = std::max(scale, std::abs(z));
  t.sf = parameters_of(sf, false, scale);
  auto sl_of = [&](double l) {
    check_nesting_index(map, l, "L-filter");
    if (l > shorter) {
      throw InputError(fmt::format(
          "L-filter: the nesting index {:g} mm is longer than the map's shorter side ({:g} mm); "
          "give a shorter one ({}) or a larger map",
          l, shorter, option_name("l_mm")));
    }
    if (o.s_mm && l <= *o.s_mm) {
      throw InputError(fmt::format(
          "L-filter: the nesting index {:g} mm must be longer than the S-filter's ({:g} mm)", l,
          *o.s_mm));
    }
    return mean_surface(sf, l, true);
  };
  HeightMap sl;
  if (o.l_mm) {
    t.l_mm = *o.l_mm;
    t.l_source = "given";
    sl = sl_of(t.l_mm);
  } else {
    // ISO 21920-3's profile table on the S-L surface's Sa, iterated from 0.8 mm as for a
    // profile (ISO 25178-3 leaves the nesting index to the specification).
    // The series is bounded by the map: two sample spacings at least (a 0.05 mm simulated
    // floor resolves no 0.08 mm cut-off), the shorter side at most, longer than the S-filter;
    // where Sa's default lies outside, the nearest cut-off the map admits is taken, and said.
    const double finest = std::max(map.dx_mm, map.dy_mm);
    const auto admits = [&](double l) {
      return l >= 2 * finest && l <= shorter && (!o.s_mm || l > *o.s_mm);
    };
    const std::array<double, 5> series = {0.08, 0.25, 0.8, 2.5, 8.0};
    const auto nearest = [&](double l) {  // the admitted series value nearest to l (log scale)
      double best = 0;
      for (const double c : series) {
        if (admits(c) && (best == 0 || std::abs(std::log(c / l)) < std::abs(std::log(best / l)))) {
          best = c;
        }
      }
      return best;
    };
    t.l_mm = nearest(0.8);
    if (t.l_mm == 0) {
      throw InputError(fmt::format(
          "L-filter: the map ({} x {} points, {:g} x {:g} mm apart) admits none of ISO "
          "21920-3's cut-offs (0.08 .. 8 mm: at least two sample spacings, at most its shorter "
          "side of {:g} mm); give one ({})",
          map.nx, map.ny, map.dx_mm, map.dy_mm, shorter, option_name("l_mm")));
    }
    t.l_source = "ISO 21920-3 default from Sa";
    for (int k = 0;; ++k) {
      sl = sl_of(t.l_mm);
      const double next = default_cutoff_mm(parameters_of(sl, false, scale).sa_mm);
      if (next == t.l_mm) break;
      if (!admits(next)) {
        // The nearest the map admits instead (evaluated again, unless it is this one).
        const double instead = nearest(next);
        t.l_source = fmt::format(
            "the nearest ISO 21920-3 cut-off this map admits: the default from Sa, {:g} mm, is "
            "{} (sample spacing {:g} mm, shorter side {:g} mm)",
            next, next < t.l_mm ? "shorter than two sample spacings" : "longer than the map",
            finest, shorter);
        if (instead == t.l_mm) break;
        t.l_mm = instead;
        sl = sl_of(t.l_mm);
        break;
      }
      if (k == 3) {
        t.l_source = "ISO 21920-3 default from Sa (Sa lies at a boundary of its table)";
        break;
      }
      t.l_mm = next;
    }
  }
  t.sl = parameters_of(sl, true, scale);
  return t;
}

}  // namespace trochomill

namespace trochomill {

namespace {

// The 2-D real spectrum of a (rows x cols, row-major) zero-padded to py x px, single
// precision: rows by real FFT, then columns by complex FFT; [row][frequency along x].
FftwBuffer<fftwf_complex, float> spectrum2(const std::vector<float>& a, std::size_t cols,
                                           std::size_t rows, std::size_t px, std::size_t py,
                                           const RealPlans<float>& rp,
                                           const ComplexPlans<float>& cp) {
  using C = fftwf_complex;
  const std::size_t hx = px / 2 + 1;
  auto spec = fftw_buffer<C, float>(py * hx);
  prefer_huge_pages(spec.get(), py * hx * sizeof(C));
  struct RowWork {
    FftwBuffer<float, float> real;
    FftwBuffer<C, float> out;
  };
  tbb::enumerable_thread_specific<RowWork> rw([&] {
    return RowWork{fftw_buffer<float, float>(px), fftw_buffer<C, float>(hx)};
  });
  tbb::parallel_for(std::size_t{0}, py, [&](std::size_t r) {
    if (r >= rows) {
      std::fill(&spec[r * hx][0], &spec[r * hx][0] + 2 * hx, 0.0f);
      return;
    }
    RowWork& w = rw.local();
    std::copy(a.begin() + static_cast<std::ptrdiff_t>(r * cols),
              a.begin() + static_cast<std::ptrdiff_t>((r + 1) * cols), w.real.get());
    std::fill(w.real.get() + cols, w.real.get() + px, 0.0f);
    rp.forward(w.real.get(), w.out.get());
    std::memcpy(spec.get() + r * hx, w.out.get(), hx * sizeof(C));
  });
  struct ColWork {
    FftwBuffer<C, float> a, b;
  };
  tbb::enumerable_thread_specific<ColWork> cw([&] {
    return ColWork{fftw_buffer<C, float>(py), fftw_buffer<C, float>(py)};
  });
  tbb::parallel_for(std::size_t{0}, hx, [&](std::size_t j) {
    ColWork& w = cw.local();
    for (std::size_t r = 0; r < py; ++r) {
      w.a[r][0] = spec[r * hx + j][0], w.a[r][1] = spec[r * hx + j][1];
    }
    cp.forward(w.a.get(), w.b.get());
    for (std::size_t r = 0; r < py; ++r) {
      spec[r * hx + j][0] = w.b[r][0], spec[r * hx + j][1] = w.b[r][1];
    }
  });
  return spec;
}

// Sums of v and v^2 over rectangles: summed-area tables (double) of a rows x cols map.
struct AreaSums {
  std::size_t cols = 0;
  std::vector<double> s1, s2;  // (rows + 1) x (cols + 1)
  AreaSums(const std::vector<float>& v, std::size_t c, std::size_t rows) : cols(c) {
    s1.assign((rows + 1) * (c + 1), 0.0);
    s2.assign((rows + 1) * (c + 1), 0.0);
    for (std::size_t r = 0; r < rows; ++r) {
      double a = 0, b = 0;
      for (std::size_t i = 0; i < c; ++i) {
        const double x = v[r * c + i];
        a += x, b += x * x;
        s1[(r + 1) * (c + 1) + i + 1] = s1[r * (c + 1) + i + 1] + a;
        s2[(r + 1) * (c + 1) + i + 1] = s2[r * (c + 1) + i + 1] + b;
      }
    }
  }
  // Over columns [c0, c1) and rows [r0, r1).
  [[nodiscard]] std::pair<double, double> over(std::size_t c0, std::size_t c1, std::size_t r0,
                                               std::size_t r1) const {
    const std::size_t w = cols + 1;
    auto rect = [&](const std::vector<double>& s) {
      return s[r1 * w + c1] - s[r0 * w + c1] - s[r1 * w + c0] + s[r0 * w + c0];
    };
    return {rect(s1), rect(s2)};
  }
};

// The least-squares plane z = a + b x + c y over points (x, y, z): (a, b, c).
Eigen::Vector3d plane_fit(const std::vector<std::array<double, 3>>& p) {
  Eigen::Matrix3d n = Eigen::Matrix3d::Zero();
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  for (const auto& q : p) {
    const Eigen::Vector3d u(1.0, q[0], q[1]);
    n += u * u.transpose();
    r += u * q[2];
  }
  return n.ldlt().solve(r);
}

}  // namespace

SurfaceComparison compare_surfaces(const HeightMap& measured, const HeightMap& predicted,
                                   std::optional<double> max_shift_mm) {
  check_height_map(measured, "surface comparison (measured)");
  check_height_map(predicted, "surface comparison (predicted)");
  const HeightMap& m = measured;
  const double dx = m.dx_mm, dy = m.dy_mm;
  // The predicted surface resampled on the measured spacing over its own extent (bilinear).
  const auto qx = static_cast<std::size_t>(std::floor(
                      static_cast<double>(predicted.nx - 1) * predicted.dx_mm / dx + 1e-9)) +
                  1;
  const auto qy = static_cast<std::size_t>(std::floor(
                      static_cast<double>(predicted.ny - 1) * predicted.dy_mm / dy + 1e-9)) +
                  1;
  if (qx < 2 || qy < 2) {
    throw InputError(
        "surface comparison: the predicted surface is smaller than two measured "
        "spacings");
  }
  if (static_cast<double>(qx) * static_cast<double>(qy) >
      4.0 * static_cast<double>(m.nx * m.ny) + 1e6) {
    throw InputError(fmt::format(
        "surface comparison: the predicted surface resampled at the measured spacing has {} x "
        "{} points, over four times the measured map's: compare a predicted surface of about "
        "the measured one's size",
        qx, qy));
  }
  HeightMap q = same_grid(predicted, predicted.description);
  q.nx = qx, q.ny = qy, q.dx_mm = dx, q.dy_mm = dy;
  q.z_mm.resize(qx * qy);
  for (std::size_t j = 0; j < qy; ++j) {
    const double v = std::min(static_cast<double>(j) * dy / predicted.dy_mm,
                              static_cast<double>(predicted.ny - 1));
    const auto j0 = std::min(static_cast<std::size_t>(v), predicted.ny - 2);
    const double fy = v - static_cast<double>(j0);
    for (std::size_t i = 0; i < qx; ++i) {
      const double u = std::min(static_cast<double>(i) * dx / predicted.dx_mm,
                                static_cast<double>(predicted.nx - 1));
      const auto i0 = std::min(static_cast<std::size_t>(u), predicted.nx - 2);
      const double fx = u - static_cast<double>(i0);
      q.z_mm[j * qx + i] =
          (1 - fy) * ((1 - fx) * predicted.at(i0, j0) + fx * predicted.at(i0 + 1, j0)) +
          fy * ((1 - fx) * predicted.at(i0, j0 + 1) + fx * predicted.at(i0 + 1, j0 + 1));
    }
  }
  // The shift by the normalised cross-correlation of the two, each less its plane.
  const double side =
      std::min(static_cast<double>(m.nx - 1) * dx, static_cast<double>(m.ny - 1) * dy);
  const double reach = max_shift_mm.value_or(0.25 * side);
  if (!(std::isfinite(reach) && reach >= 0)) {
    throw InputError(
        fmt::format("surface comparison: the largest shift must be a finite number "
                    ">= 0 mm, got {}",
                    reach));
  }
  // The natural offset (the two origins) and the search around it, in measured samples.
  const long kx0 = std::lround((q.x0_mm - m.x0_mm) / dx),
             ky0 = std::lround((q.y0_mm - m.y0_mm) / dy);
  const long sx = std::min<long>(std::lround(reach / dx), static_cast<long>(std::max(m.nx, qx))),
             sy = std::min<long>(std::lround(reach / dy), static_cast<long>(std::max(m.ny, qy)));
  const HeightMap mp = form_removed(m, FormRemoval::plane, 1);
  const HeightMap qp = form_removed(q, FormRemoval::plane, 1);
  std::vector<float> a(qx * qy), b(m.nx * m.ny);
  for (std::size_t i = 0; i < a.size(); ++i) a[i] = static_cast<float>(qp.z_mm[i]);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<float>(mp.z_mm[i]);
  // C(k) = sum_i Q(i) M(i + k) for k in [k0 - s, k0 + s]: Q placed at k0 (its origin), the
  // circular correlation of a size with room for the shifts.
  const std::size_t px =
      fast_fft_size(std::max(m.nx, qx) + static_cast<std::size_t>(std::abs(kx0) + sx) + 1);
  const std::size_t py =
      fast_fft_size(std::max(m.ny, qy) + static_cast<std::size_t>(std::abs(ky0) + sy) + 1);
  if (static_cast<double>(px) * static_cast<double>(py) > 3e8) {
    throw InputError(
        "surface comparison: the shift search is too large (give a smaller "
        "largest shift, or surfaces placed closer to each other)");
  }
  const RealPlans<float> rp(px);
  const ComplexPlans<float> cp(py);
  auto fa = spectrum2(a, qx, qy, px, py, rp, cp);
  auto fb = spectrum2(b, m.nx, m.ny, px, py, rp, cp);
  const std::size_t hx = px / 2 + 1;
  for (std::size_t i = 0; i < hx * py; ++i) {  // conj(A) B
    const float ar = fa[i][0], ai = fa[i][1], br = fb[i][0], bi = fb[i][1];
    fb[i][0] = ar * br + ai * bi;
    fb[i][1] = ar * bi - ai * br;
  }
  fa.reset();
  // Back: columns (in parallel, each on its own buffers, as spectrum2 runs them), then the
  // rows of the lags searched.
  {
    struct ColWork {
      FftwBuffer<fftwf_complex, float> a, b;
    };
    tbb::enumerable_thread_specific<ColWork> cw([&] {
      return ColWork{fftw_buffer<fftwf_complex, float>(py), fftw_buffer<fftwf_complex, float>(py)};
    });
    tbb::parallel_for(std::size_t{0}, hx, [&](std::size_t j) {
      ColWork& w = cw.local();
      for (std::size_t r = 0; r < py; ++r) {
        w.a[r][0] = fb[r * hx + j][0], w.a[r][1] = fb[r * hx + j][1];
      }
      cp.inverse(w.a.get(), w.b.get());
      for (std::size_t r = 0; r < py; ++r) {
        fb[r * hx + j][0] = w.b[r][0], fb[r * hx + j][1] = w.b[r][1];
      }
    });
  }
  const AreaSums qs(a, qx, qy), ms(b, m.nx, m.ny);
  const double min_points = 0.5 * static_cast<double>(std::min(qx * qy, m.nx * m.ny));
  double best = -2;
  long bx = 0, by = 0;
  auto row = fftw_buffer<float, float>(px);
  auto in = fftw_buffer<fftwf_complex, float>(hx);
  const double scale = 1.0 / (static_cast<double>(px) * static_cast<double>(py));
  for (long ky = ky0 - sy; ky <= ky0 + sy; ++ky) {
    const std::size_t rr = static_cast<std::size_t>(
        (ky % static_cast<long>(py) + static_cast<long>(py)) % static_cast<long>(py));
    std::memcpy(in.get(), fb.get() + rr * hx, hx * sizeof(fftwf_complex));
    rp.inverse(in.get(), row.get());
    // Rows of Q with a measured row at +ky.
    const long j0 = std::max<long>(0, -ky),
               j1 = std::min<long>(static_cast<long>(qy), static_cast<long>(m.ny) - ky);
    if (j1 <= j0) continue;
    for (long kx = kx0 - sx; kx <= kx0 + sx; ++kx) {
      const long i0 = std::max<long>(0, -kx),
                 i1 = std::min<long>(static_cast<long>(qx), static_cast<long>(m.nx) - kx);
      if (i1 <= i0) continue;
      const double n = static_cast<double>((i1 - i0) * (j1 - j0));
      if (n < min_points) continue;
      const auto [sq1, sq2] = qs.over(static_cast<std::size_t>(i0), static_cast<std::size_t>(i1),
                                      static_cast<std::size_t>(j0), static_cast<std::size_t>(j1));
      const auto [sm1, sm2] =
          ms.over(static_cast<std::size_t>(i0 + kx), static_cast<std::size_t>(i1 + kx),
                  static_cast<std::size_t>(j0 + ky), static_cast<std::size_t>(j1 + ky));
      const std::size_t cc = static_cast<std::size_t>(
          (kx % static_cast<long>(px) + static_cast<long>(px)) % static_cast<long>(px));
      const double c = static_cast<double>(row[cc]) * scale;
      const double vq = sq2 - sq1 * sq1 / n, vm = sm2 - sm1 * sm1 / n;
      if (!(vq > 0 && vm > 0)) continue;
      const double ncc = (c - sq1 * sm1 / n) / std::sqrt(vq * vm);
      if (ncc > best) best = ncc, bx = kx, by = ky;
    }
  }
  if (best < -1.5) {
    throw InputError(fmt::format(
        "surface comparison: no shift within {:g} mm leaves half of the smaller surface "
        "overlapping the other (or one of them is flat): place them closer or allow a larger "
        "shift",
        reach));
  }
  SurfaceComparison out;
  out.correlation = best;
  // measured(i + k) against predicted(i): the predicted point at x_q(i) lies on the measured
  // point at x_m(i + k); the shift is how far that is from where the coordinates put it.
  out.shift_x_mm = static_cast<double>(bx) * dx + m.x0_mm - q.x0_mm;
  out.shift_y_mm = static_cast<double>(by) * dy + m.y0_mm - q.y0_mm;
  const long i0 = std::max<long>(0, -bx),
             i1 = std::min<long>(static_cast<long>(qx), static_cast<long>(m.nx) - bx);
  const long j0 = std::max<long>(0, -by),
             j1 = std::min<long>(static_cast<long>(qy), static_cast<long>(m.ny) - by);
  const auto ox = static_cast<std::size_t>(i1 - i0), oy = static_cast<std::size_t>(j1 - j0);
  std::vector<std::array<double, 3>> diff;
  diff.reserve(ox * oy);
  HeightMap mo = same_grid(m, m.description), qo = same_grid(q, q.description);
  mo.nx = qo.nx = ox, mo.ny = qo.ny = oy;
  for (long j = j0; j < j1; ++j) {
    for (long i = i0; i < i1; ++i) {
      const double zm = m.at(static_cast<std::size_t>(i + bx), static_cast<std::size_t>(j + by));
      const double zq = q.at(static_cast<std::size_t>(i), static_cast<std::size_t>(j));
      mo.z_mm.push_back(zm), qo.z_mm.push_back(zq);
      diff.push_back({static_cast<double>(i - i0) * dx, static_cast<double>(j - j0) * dy, zm - zq});
    }
  }
  const Eigen::Vector3d pl = plane_fit(diff);
  out.tilt_x = pl(1), out.tilt_y = pl(2);
  double s2 = 0, mx = 0, sum = 0;
  for (const auto& d : diff) {
    const double r = d[2] - (pl(0) + pl(1) * d[0] + pl(2) * d[1]);
    s2 += r * r, mx = std::max(mx, std::abs(r)), sum += d[2];
  }
  out.offset_mm = sum / static_cast<double>(diff.size());
  out.points = diff.size();
  out.rms_difference_mm = std::sqrt(s2 / static_cast<double>(diff.size()));
  out.max_difference_mm = mx;
  out.overlap_mm2 = static_cast<double>(ox - 1) * dx * static_cast<double>(oy - 1) * dy;
  if (ox >= 2 && oy >= 2) {
    const HeightMap mf = form_removed(std::move(mo), FormRemoval::plane, 1);
    const HeightMap qf = form_removed(std::move(qo), FormRemoval::plane, 1);
    out.measured = parameters_of(mf, false);
    out.predicted = parameters_of(qf, false);
    // The correlation reported: over the overlap, each less its plane there (the search's
    // used each map's plane over the whole map).
    double smq = 0, smm = 0, sqq = 0;
    for (std::size_t k = 0; k < mf.z_mm.size(); ++k) {
      smq += mf.z_mm[k] * qf.z_mm[k], smm += mf.z_mm[k] * mf.z_mm[k],
          sqq += qf.z_mm[k] * qf.z_mm[k];
    }
    out.correlation = smm > 0 && sqq > 0 ? smq / std::sqrt(smm * sqq) : 0.0;
  }
  return out;
}

}  // namespace trochomill
