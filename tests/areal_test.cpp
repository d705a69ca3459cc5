// Areal surface texture: the ISO 16610-61 Gaussian filter, form removal and the ISO 25178-2
// parameters against closed forms, the profile filter and scipy; X3P written, read back and
// refused when malformed.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <tbb/task_arena.h>
#include <unistd.h>
#include <zip.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/surface.hpp"

namespace trochomill {
namespace {

namespace fs = std::filesystem;

template <class F>
HeightMap map_of(std::size_t nx, std::size_t ny, double dx, double dy, F&& z) {
  HeightMap m;
  m.nx = nx, m.ny = ny, m.dx_mm = dx, m.dy_mm = dy;
  m.z_mm.resize(nx * ny);
  for (std::size_t r = 0; r < ny; ++r) {
    for (std::size_t c = 0; c < nx; ++c) {
      m.z_mm[r * nx + c] = z(static_cast<double>(c) * dx, static_cast<double>(r) * dy);
    }
  }
  return m;
}

ArealFilterOptions filters(std::optional<double> s_mm, std::optional<double> l_mm) {
  ArealFilterOptions o;
  o.s_mm = s_mm, o.l_mm = l_mm;
  return o;
}

X3pInfo dated(const std::string& date, const std::string& creator = "") {
  X3pInfo i;
  i.date = date, i.creator = creator;
  return i;
}

// z = A sin(2 pi x / lambda) over 40 whole periods of 2000 samples: the discrete means of
// |sin| and sin^2 over whole periods are 2/pi to (pi/2N)^2/6 = 1e-7 and exactly 1/2, so Sa =
// 2A/pi and Sq = A/sqrt 2 to 1e-6; the crest and trough are samples: Sp = Sv = A. Sdr from the
// cells' finite differences against the integral (1/lambda) int sqrt(1 + (A k cos kx)^2) dx
// by Simpson's rule on 1e5 intervals, to 1e-4 (the difference quotient's error is
// (k dx)^2 / 24 of the slope: 4e-7 here). The autocorrelation of a sinusoid is cos(k t) along
// x and 1 along y: Sal = acos(0.2) / k, to 1 % (the estimate over a finite map adds a term of
// order 1 / (4 pi periods) to the cosine), and no Str (it never decays along y).
TEST(Areal, SinusoidParametersMatchTheirClosedForms) {
  const double A = 0.002, lambda = 0.2;
  const std::size_t per = 2000, periods = 40;
  const double dx = lambda / per;
  const HeightMap m = map_of(per * periods, 3, dx, dx, [&](double x, double) {
    return A * std::sin(2 * std::numbers::pi * x / lambda);
  });
  const ArealParameters p = areal_parameters(m, false);
  EXPECT_NEAR(p.sa_mm / (2 * A / std::numbers::pi), 1.0, 1e-6);
  EXPECT_NEAR(p.sq_mm / (A / std::sqrt(2.0)), 1.0, 1e-6);
  EXPECT_NEAR(p.sp_mm / A, 1.0, 1e-6);
  EXPECT_NEAR(p.sv_mm / A, 1.0, 1e-6);
  EXPECT_NEAR(p.sz_mm / (2 * A), 1.0, 1e-6);
  EXPECT_NEAR(p.ssk, 0.0, 1e-6);
  EXPECT_NEAR(p.sku, 1.5, 1e-6);
  const double k = 2 * std::numbers::pi / lambda;
  const int n = 100000;
  double integral = 0;
  for (int i = 0; i <= n; ++i) {
    const double x = lambda * i / n, s = A * k * std::cos(k * x);
    integral += (i == 0 || i == n ? 1 : (i % 2 ? 4 : 2)) * std::sqrt(1 + s * s);
  }
  integral *= lambda / n / 3;
  const double sdr = 100 * (integral / lambda - 1);
  EXPECT_NEAR(p.sdr_percent / sdr, 1.0, 1e-4) << p.sdr_percent << " vs " << sdr;

  // The autocorrelation on a smaller map (2 periods of 200 samples... 40 periods of 50).
  const HeightMap small = map_of(50 * 40, 64, lambda / 50, lambda / 50, [&](double x, double) {
    return A * std::sin(2 * std::numbers::pi * x / lambda);
  });
  const ArealParameters q = areal_parameters(small, true);
  ASSERT_TRUE(q.sal_mm.has_value());
  EXPECT_NEAR(*q.sal_mm / (std::acos(0.2) / k), 1.0, 0.01);
  EXPECT_FALSE(q.str.has_value());
}

// z = cos(kx) cos(ky): its autocorrelation is cos(k tx) cos(k ty), which decays to 0.2
// first along the axes (r = acos(0.2) / k) and last along the diagonals (cos^2(k r / sqrt 2)
// = 0.2: r = sqrt 2 acos(sqrt 0.2) / k), so Str = acos(0.2) / (sqrt 2 acos(sqrt 0.2)) =
// 0.8746. To 1.5 %: the finite-map term as above, in both directions of the ratio.
TEST(Areal, TextureAspectRatioOfACheckerboard) {
  const double lambda = 0.1, k = 2 * std::numbers::pi / lambda, d = lambda / 40;
  const HeightMap m = map_of(40 * 24, 40 * 24, d, d, [&](double x, double y) {
    return 0.001 * std::cos(k * x) * std::cos(k * y);
  });
  const ArealParameters p = areal_parameters(m, true);
  ASSERT_TRUE(p.sal_mm && p.str);
  EXPECT_NEAR(*p.sal_mm / (std::acos(0.2) / k), 1.0, 0.015);
  EXPECT_NEAR(*p.str / (std::acos(0.2) / (std::sqrt(2.0) * std::acos(std::sqrt(0.2)))), 1.0, 0.015);
}

// The areal filter's mean surface transmits a wave of wavelength lambda at the standard's
// exp(-pi (alpha lambda_c / lambda)^2), along x and along y: measured by the least-squares
// amplitude over the map's middle (a cut-off from the edges), to 1e-4 (the kernel is cut at
// +-lambda_c, where it is 6.5e-7 of its peak; sampling at lambda_c / 100).
TEST(Areal, FilterTransmitsAsTheStandardSays) {
  const double lc = 0.8, dx = lc / 100;
  const double alpha = std::sqrt(std::log(2.0) / std::numbers::pi);
  for (const double lambda : {0.4, 0.8, 1.6, 3.2}) {
    for (const bool along_x : {true, false}) {
      const std::size_t n = 1000, m = 12;
      const HeightMap h = map_of(along_x ? n : m, along_x ? m : n, dx, dx, [&](double x, double y) {
        return std::sin(2 * std::numbers::pi * (along_x ? x : y) / lambda);
      });
      const HeightMap f = gaussian_filter_areal(h, lc);
      // Amplitude of sin and cos over the middle samples of one line.
      double ss = 0, sc = 0, s2 = 0, c2 = 0;
      for (std::size_t i = 100; i + 100 < n; ++i) {
        const double u = 2 * std::numbers::pi * static_cast<double>(i) * dx / lambda;
        const double v = along_x ? f.at(i, m / 2) : f.at(m / 2, i);
        ss += v * std::sin(u), sc += v * std::cos(u);
        s2 += std::sin(u) * std::sin(u), c2 += std::cos(u) * std::cos(u);
      }
      const double amp = std::hypot(ss / s2, sc / c2);
      const double want = std::exp(-std::numbers::pi * std::pow(alpha * lc / lambda, 2));
      EXPECT_NEAR(amp, want, 1e-4) << "lambda " << lambda << (along_x ? " along x" : " along y");
      EXPECT_NEAR(want, gaussian_transmission(lambda, lc), 1e-15);
    }
  }
}

// Every row of the areal filter's first pass is the profile filter with renormalised ends
// (the profile filter convolves directly; the areal one by FFT when the kernel is long, as
// here): the same numbers to 1e-12 of the heights (FFT rounding). On a map constant along y
// the second pass changes nothing (its weights sum to one everywhere).
TEST(Areal, FftFilterAgreesWithTheDirectProfileFilter) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 0.003);
  std::vector<double> row(700);
  for (double& v : row) v = g(rng);
  const double dx = 0.004, lc = 0.8;  // 401 weights: the FFT path
  HeightMap m;
  m.nx = row.size(), m.ny = 5, m.dx_mm = dx, m.dy_mm = dx;
  for (std::size_t r = 0; r < m.ny; ++r) m.z_mm.insert(m.z_mm.end(), row.begin(), row.end());
  const HeightMap f = gaussian_filter_areal(m, lc);
  const FilteredProfile p = gaussian_filter(row, dx, lc, FilterEnds::normalize);
  for (std::size_t r = 0; r < m.ny; ++r) {
    for (std::size_t c = 0; c < m.nx; ++c) {
      ASSERT_NEAR(f.at(c, r), p.mean_mm[c], 1e-12 * 0.003) << c << ", " << r;
    }
  }
  // A short kernel (direct convolution) agrees too.
  const HeightMap fs = gaussian_filter_areal(m, 0.08);  // 41 weights
  const FilteredProfile ps = gaussian_filter(row, dx, 0.08, FilterEnds::normalize);
  for (std::size_t c = 0; c < m.nx; ++c) ASSERT_NEAR(fs.at(c, 2), ps.mean_mm[c], 1e-15);
}

// The results do not depend on the thread count (every line runs the same plan on its own
// buffer): bit for bit with 1 and with 2 threads.
TEST(Areal, ResultsDoNotDependOnTheThreadCount) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  const HeightMap m = map_of(300, 200, 0.005, 0.004, [&](double, double) { return u(rng); });
  ArealTexture one, two;
  tbb::task_arena(1).execute([&] { one = areal_texture(m, filters(0.025, 0.25)); });
  tbb::task_arena(2).execute([&] { two = areal_texture(m, filters(0.025, 0.25)); });
  EXPECT_EQ(one.sl.sa_mm, two.sl.sa_mm);
  EXPECT_EQ(one.sl.sdr_percent, two.sl.sdr_percent);
  EXPECT_EQ(one.sl.sal_mm, two.sl.sal_mm);
  EXPECT_EQ(one.sf.sq_mm, two.sf.sq_mm);
}

// Form removal: a polynomial of the removed degree leaves nothing (to 1e-12 of its size, the
// normal equations in Legendre polynomials being well conditioned); a plane removes a tilt
// and keeps a wave along y orthogonal to it on whole periods.
TEST(Areal, FormRemovalTakesOutPlanesAndPolynomials) {
  const auto poly = [](double x, double y) {
    return 0.3 + 0.02 * x - 0.05 * y + 0.01 * x * x * y - 0.003 * y * y * y + 0.002 * x * y;
  };
  const HeightMap m = map_of(120, 90, 0.05, 0.07, poly);
  const HeightMap r = remove_form(m, FormRemoval::polynomial, 3);
  for (const double v : r.z_mm) ASSERT_NEAR(v, 0.0, 1e-12);
  const HeightMap left = remove_form(m, FormRemoval::polynomial, 2);
  double worst = 0;
  for (const double v : left.z_mm) worst = std::max(worst, std::abs(v));
  EXPECT_GT(worst, 1e-4);  // degree 2 cannot take out the cubic terms
  const HeightMap tilt = map_of(101, 80, 0.01, 0.0125, [](double x, double y) {
    return 0.1 * x - 0.2 * y + 0.001 * std::cos(2 * std::numbers::pi * y);  // y spans 0..0.9875
  });
  const ArealParameters p = areal_parameters(remove_form(tilt, FormRemoval::plane), false);
  EXPECT_NEAR(p.sq_mm / (0.001 / std::sqrt(2.0)), 1.0, 0.02);  // the wave, not the tilt
  EXPECT_NE(test::message_of([&] {
              (void)remove_form(m, FormRemoval::polynomial, 9);
            }).find("degree must be 1 to 6"),
            std::string::npos);
}

// The default nesting index fits the map: a flat 0.05 mm map (a coarse simulation's floor)
// has Sa 0, whose ISO 21920-3 default (0.08 mm) is shorter than two spacings: the nearest
// cut-off it admits (0.25 mm) is taken and said (it was an error); a map too small for any
// ISO cut-off says so and asks for one.
TEST(Areal, TheDefaultNestingIndexFitsTheMap) {
  const HeightMap m = map_of(101, 101, 0.05, 0.05, [](double, double) { return 0.0; });
  const ArealTexture t = areal_texture(m, filters({}, std::nullopt));
  EXPECT_EQ(t.l_mm, 0.25);
  EXPECT_NE(t.l_source.find("the nearest ISO 21920-3 cut-off this map admits"), std::string::npos)
      << t.l_source;
  const HeightMap tiny = map_of(5, 5, 0.05, 0.05, [](double, double) { return 0.0; });
  EXPECT_NE(test::message_of([&] {
              (void)areal_texture(tiny, filters({}, std::nullopt));
            }).find("admits none of ISO 21920-3's cut-offs"),
            std::string::npos);
}

TEST(Areal, BadMapsAndNestingIndicesAreRefused) {
  HeightMap m = map_of(10, 10, 0.01, 0.01, [](double, double) { return 0.0; });
  EXPECT_NE(
      test::message_of([&] { (void)gaussian_filter_areal(m, 0.015); }).find("two sample spacings"),
      std::string::npos);
  EXPECT_NE(
      test::message_of([&] { (void)areal_texture(m, filters({}, 0.5)); }).find("shorter side"),
      std::string::npos);
  EXPECT_NE(test::message_of([&] {
              (void)areal_texture(m, filters(0.05, 0.04));
            }).find("longer than the S-filter"),
            std::string::npos);
  m.z_mm[23] = std::nan("");
  EXPECT_NE(test::message_of([&] { (void)areal_parameters(m); }).find("column 3, row 2"),
            std::string::npos);
  m.z_mm.pop_back();
  EXPECT_NE(test::message_of([&] { (void)areal_parameters(m); }).find("99 heights for 10 x 10"),
            std::string::npos);
  EXPECT_NE(test::message_of([&] {
              (void)gaussian_filter_areal(
                  map_of(10, 10, 1e-9, 1e-9, [](double, double) { return 0.0; }), 1.0);
            }).find("(limit 5e+07)"),
            std::string::npos);
}

// scipy (a real peer): the standard's weights through scipy.ndimage.correlate1d along each
// axis with zero padding, divided by the same of ones (the renormalised ends), and Sa, Sq,
// Ssk, Sku, Sz, Sdr with numpy, on a random map; the same numbers to 1e-10 relative
// (rounding in different orders of summation).
TEST(Areal, AgreesWithScipy) {
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  if (std::system((python + " -c 'import scipy.ndimage' > /dev/null 2>&1").c_str()) != 0) {
    GTEST_SKIP() << "scipy is not installed: scripts/install-deps --test installs python3-scipy";
  }
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 0.002);
  const HeightMap m = map_of(160, 120, 0.005, 0.004, [&](double, double) { return g(rng); });
  const double lc = 0.25;
  const fs::path dir = fs::temp_directory_path() / fmt::format("trochomill-scipy-{}", getpid());
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "z.txt");
    out.precision(17);
    for (std::size_t r = 0; r < m.ny; ++r) {
      for (std::size_t c = 0; c < m.nx; ++c) out << m.at(c, r) << (c + 1 < m.nx ? ' ' : '\n');
    }
  }
  const std::string script = fmt::format(R"(
import numpy as np, scipy.ndimage as nd
z = np.loadtxt('{dir}/z.txt'); dx, dy, lc = 0.005, 0.004, {lc}
alpha = np.sqrt(np.log(2) / np.pi)
def filt(a, d, axis):
    h = int(np.floor(lc / d)); x = np.arange(-h, h + 1) * d
    w = np.exp(-np.pi * (x / (alpha * lc)) ** 2); w /= w.sum()
    num = nd.correlate1d(a, w, axis=axis, mode='constant', cval=0.0)
    den = nd.correlate1d(np.ones_like(a), w, axis=axis, mode='constant', cval=0.0)
    return num / den
mean = filt(filt(z, dx, 1), dy, 0)
np.savetxt('{dir}/mean.txt', mean, fmt='%.17g')
r = z - mean; e = r - r.mean(); sq = np.sqrt((e ** 2).mean())
gx = 0.5 * ((r[:-1, 1:] - r[:-1, :-1]) + (r[1:, 1:] - r[1:, :-1])) / dx
gy = 0.5 * ((r[1:, :-1] - r[:-1, :-1]) + (r[1:, 1:] - r[:-1, 1:])) / dy
sdr = 100 * (np.sqrt(1 + gx ** 2 + gy ** 2).mean() - 1)
print(np.abs(e).mean(), sq, (e ** 3).mean() / sq ** 3, (e ** 4).mean() / sq ** 4, e.max() - e.min(), sdr)
)",
                                         fmt::arg("dir", dir.string()), fmt::arg("lc", lc));
  write_file_atomic(dir / "peer.py", script);
  const std::string cmd =
      python + " " + (dir / "peer.py").string() + " > " + (dir / "out.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << read_file(dir / "out.txt");
  std::istringstream peer(read_file(dir / "out.txt"));
  double sa, sq, ssk, sku, sz, sdr;
  peer >> sa >> sq >> ssk >> sku >> sz >> sdr;
  ASSERT_FALSE(peer.fail()) << read_file(dir / "out.txt");

  const HeightMap mean = gaussian_filter_areal(m, lc);
  std::istringstream means(read_file(dir / "mean.txt"));
  for (std::size_t i = 0; i < m.z_mm.size(); ++i) {
    double v;
    means >> v;
    ASSERT_NEAR(mean.z_mm[i], v, 1e-10 * 0.002) << i;
  }
  HeightMap rough = m;
  for (std::size_t i = 0; i < m.z_mm.size(); ++i) rough.z_mm[i] -= mean.z_mm[i];
  const ArealParameters p = areal_parameters(rough, false);
  EXPECT_NEAR(p.sa_mm / sa, 1.0, 1e-10);
  EXPECT_NEAR(p.sq_mm / sq, 1.0, 1e-10);
  EXPECT_NEAR(p.ssk, ssk, 1e-9);
  EXPECT_NEAR(p.sku / sku, 1.0, 1e-10);
  EXPECT_NEAR(p.sz_mm / sz, 1.0, 1e-10);
  EXPECT_NEAR(p.sdr_percent / sdr, 1.0, 1e-9);
  fs::remove_all(dir);
}

// A measured surface against a predicted one: the measured is the predicted shape moved by
// (0.07, -0.05) mm (7 and -5 samples), set up 2 um higher and tilted by (0.01, -0.005):
// compare_surfaces finds the shift exactly, the plane's tilt to 1e-9 and leaves a difference
// of rounding only (1e-12 mm); the two surfaces' parameters over the overlap agree to 1e-9.
// A shift beyond the allowed search is not found.
TEST(Areal, CompareSurfacesAlignsAShiftedTiltedCopy) {
  const auto f = [](double x, double y) {
    return 0.003 * std::sin(2 * std::numbers::pi * (x / 0.37 + y / 0.91)) +
           0.002 * std::cos(2 * std::numbers::pi * (x / 0.23 - y / 0.41)) +
           0.001 * std::sin(2 * std::numbers::pi * x * y / 0.5);
  };
  HeightMap predicted = map_of(200, 150, 0.01, 0.01, f);
  HeightMap measured = map_of(220, 160, 0.01, 0.01, [&](double x, double y) {
    const double X = x + 0.3, Y = y - 0.2;  // the measured map's origin
    return f(X - 0.07, Y + 0.05) + 0.002 + 0.01 * X - 0.005 * Y;
  });
  measured.x0_mm = 0.3, measured.y0_mm = -0.2;
  const SurfaceComparison c = compare_surfaces(measured, predicted, 0.2);
  EXPECT_NEAR(c.shift_x_mm, 0.07, 1e-12);
  EXPECT_NEAR(c.shift_y_mm, -0.05, 1e-12);
  EXPECT_NEAR(c.tilt_x, 0.01, 1e-9);
  EXPECT_NEAR(c.tilt_y, -0.005, 1e-9);
  EXPECT_LT(c.rms_difference_mm, 1e-12);
  EXPECT_LT(c.max_difference_mm, 1e-11);
  EXPECT_NEAR(c.correlation, 1.0, 1e-9);
  EXPECT_NEAR(c.measured.sq_mm / c.predicted.sq_mm, 1.0, 1e-9);
  EXPECT_GT(c.points, 150u * 140u);
  // Not allowed to look that far: the best match within 0.03 mm is another one, worse.
  const SurfaceComparison near = compare_surfaces(measured, predicted, 0.03);
  EXPECT_FALSE(std::abs(near.shift_x_mm - 0.07) < 1e-9 && std::abs(near.shift_y_mm + 0.05) < 1e-9);
  EXPECT_GT(near.rms_difference_mm, 1e-5);
  EXPECT_NE(test::message_of([&] {
              (void)compare_surfaces(measured, predicted, -1.0);
            }).find("largest shift"),
            std::string::npos);
}

// ---- X3P ---------------------------------------------------------------------------------

fs::path scratch(const std::string& name) { return test::scratch_dir("x3p") / name; }

// Writes an archive of the given entries (name, content).
void write_zip(const fs::path& file, const std::vector<std::pair<std::string, std::string>>& e) {
  int err = 0;
  zip_t* z = zip_open(file.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &err);
  ASSERT_NE(z, nullptr);
  for (const auto& [name, content] : e) {
    zip_source_t* s = zip_source_buffer(z, content.data(), content.size(), 0);
    ASSERT_GE(zip_file_add(z, name.c_str(), s, ZIP_FL_OVERWRITE), 0);
  }
  ASSERT_EQ(zip_close(z), 0);
}

std::vector<std::pair<std::string, std::string>> read_zip(const fs::path& file) {
  std::vector<std::pair<std::string, std::string>> out;
  int err = 0;
  zip_t* z = zip_open(file.c_str(), ZIP_RDONLY, &err);
  if (z == nullptr) return out;
  for (zip_int64_t i = 0; i < zip_get_num_entries(z, 0); ++i) {
    zip_stat_t st;
    zip_stat_index(z, static_cast<zip_uint64_t>(i), 0, &st);
    std::string content(st.size, '\0');
    zip_file_t* f = zip_fopen_index(z, static_cast<zip_uint64_t>(i), 0);
    zip_fread(f, content.data(), st.size);
    zip_fclose(f);
    out.emplace_back(st.name, content);
  }
  zip_discard(z);
  return out;
}

std::string replaced(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// A write that fails (past the file size limit, as a full disk fails it): IoError naming the
// file, and nothing left in its folder. In a child process, whose limit alone is set.
TEST(X3p, AFailedWriteNamesTheFileAndLeavesNothing) {
  const fs::path dir = scratch("full");
  fs::create_directories(dir);
  const fs::path file = dir / "floor.x3p";
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  const HeightMap m = map_of(300, 300, 0.01, 0.01, [&](double, double) { return u(rng); });
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    std::signal(SIGXFSZ, SIG_IGN);
    const rlimit lim{64 * 1024, 64 * 1024};  // the map is 720 kB of doubles, compressed
    (void)::setrlimit(RLIMIT_FSIZE, &lim);
    int code = 3;
    try {
      write_x3p(file, m, dated("2026-12-04T12:00:00+00:00", "the test"));
      code = 4;  // written: the limit did not bite
    } catch (const IoError& e) {
      code = std::string(e.what()).find(file.string()) != std::string::npos ? 0 : 5;
    } catch (...) {
      code = 6;
    }
    ::_exit(code);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "3: no error, 4: written, 5: the file not named, 6: "
                                       "another exception";
  EXPECT_TRUE(fs::is_empty(dir)) << "a partial archive or temporary file was left";
}

// Written and read back: the same grid, heights to within one rounding (mm to m and back),
// the description; written again from what was read, the archive is the same bytes (the
// metres written are those read: m / 1000 * 1000 / 1000 = m / 1000 for every double tried).
TEST(X3p, WrittenAndReadBackIsIdentical) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  HeightMap m = map_of(37, 23, 0.0025, 0.005, [&](double, double) { return u(rng); });
  m.x0_mm = 1.5, m.y0_mm = -2.25;
  m.description = "floor <of> a slot & more";
  const X3pInfo info = dated("2026-11-30T12:00:00+00:00", "the test");
  const fs::path a = scratch("a.x3p"), b = scratch("b.x3p");
  write_x3p(a, m, info);
  X3pInfo got;
  const HeightMap back = read_x3p(a, &got);
  EXPECT_EQ(back.nx, m.nx);
  EXPECT_EQ(back.ny, m.ny);
  EXPECT_EQ(back.dx_mm, m.dx_mm);  // the increment's decimal text shifted by 10^3: exact
  EXPECT_EQ(back.dy_mm, m.dy_mm);
  EXPECT_EQ(back.x0_mm, m.x0_mm);
  EXPECT_EQ(back.y0_mm, m.y0_mm);
  for (std::size_t i = 0; i < m.z_mm.size(); ++i) {
    ASSERT_NEAR(back.z_mm[i], m.z_mm[i], 2.3e-16 * std::abs(m.z_mm[i])) << i;  // one ulp
  }
  EXPECT_EQ(got.comment, m.description);
  EXPECT_EQ(got.creator, "the test");
  EXPECT_EQ(got.date, info.date);
  write_x3p(b, back, got);  // what was read, written again
  EXPECT_TRUE(read_file(a) == read_file(b)) << "the archives differ";
  // The archive holds what the format names, with the checksums it states.
  const auto entries = read_zip(a);
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[0].first, "main.xml");
  EXPECT_EQ(entries[1].first, "bindata/data.bin");
  EXPECT_EQ(entries[1].second.size(), m.z_mm.size() * 8);
  EXPECT_EQ(entries[2].first, "md5checksum.hex");
  EXPECT_NE(entries[2].second.find(" *main.xml"), std::string::npos);
  // A profile (ny = 1) is written and read as one.
  HeightMap prf = map_of(50, 1, 0.001, 0.001, [](double x, double) { return 0.001 * x; });
  write_x3p(b, prf, info);
  const HeightMap pb = read_x3p(b);
  EXPECT_EQ(pb.ny, 1u);
  EXPECT_NE(pb.description.find("X3P profile"), std::string::npos);
}

// Other instruments' files: int16 heights scaled by CZ's increment and offset, and points
// listed in main.xml (DataList).
TEST(X3p, ReadsIntegerDataAndDataLists) {
  const fs::path a = scratch("c.x3p");
  write_x3p(a, map_of(4, 3, 0.001, 0.001, [](double, double) { return 0.0; }),
            dated("2026-01-01T00:00:00+00:00"));
  auto e = read_zip(a);
  std::string xml = e[0].second;
  xml = replaced(
      xml, "<DataType>D</DataType>\n        <Increment>1</Increment>\n        <Offset>0</Offset>",
      "<DataType>I</DataType>\n        <Increment>1e-8</Increment>\n        <Offset>2e-6</Offset>");
  std::string bin(24, '\0');
  for (int i = 0; i < 12; ++i) {
    const auto v = static_cast<std::int16_t>(100 * i - 500);
    std::memcpy(bin.data() + 2 * i, &v, 2);
  }
  const auto md5_start = xml.find("<MD5ChecksumPointData>");
  const auto md5_end = xml.find("</MD5ChecksumPointData>");
  xml.erase(md5_start, md5_end + 23 - md5_start);  // no checksum: not checked
  write_zip(a, {{"main.xml", xml}, {"bindata/data.bin", bin}});
  const HeightMap m = read_x3p(a);
  for (int i = 0; i < 12; ++i) {
    // (100 i - 500) * 1e-8 m + 2e-6 m, in mm: exact decimal scaling to rounding.
    EXPECT_NEAR(m.z_mm[static_cast<std::size_t>(i)], (100.0 * i - 500) * 1e-5 + 2e-3, 1e-15);
  }
  // The same heights listed in main.xml.
  std::string list = "<DataList>";
  for (int i = 0; i < 12; ++i) list += fmt::format("<Datum>{}</Datum>", 100 * i - 500);
  list += "</DataList>";
  const auto link_start = xml.find("<DataLink>");
  const auto link_end = xml.find("</DataLink>") + 11;
  std::string listed = xml;
  listed.replace(link_start, link_end - link_start, list);
  write_zip(a, {{"main.xml", listed}});
  const HeightMap l = read_x3p(a);
  EXPECT_EQ(l.z_mm, m.z_mm);
}

// Malformed archives and XML are refused with what is wrong and where.
TEST(X3p, MalformedFilesAreRefusedWithTheReason) {
  const fs::path good = scratch("good.x3p"), bad = scratch("bad.x3p");
  write_x3p(good, map_of(5, 4, 0.001, 0.001, [](double x, double y) { return x - y; }),
            dated("2026-01-01T00:00:00+00:00"));
  const auto e = read_zip(good);
  const std::string xml = e[0].second, bin = e[1].second;
  auto refused = [&](const std::string& what) {
    const std::string m = test::message_of([&] { (void)read_x3p(bad); });
    if (m.find(what) != std::string::npos) return true;
    ADD_FAILURE() << "expected '" << what << "' in: " << m;
    return false;
  };
  write_file_atomic(bad, "not a zip at all");
  EXPECT_TRUE(refused("not an X3P file: the zip archive cannot be opened"));
  write_file_atomic(bad, read_file(good).substr(0, 100));  // truncated archive
  EXPECT_TRUE(refused("not an X3P file"));
  write_zip(bad, {{"bindata/data.bin", bin}});
  EXPECT_TRUE(refused("the archive has no 'main.xml'"));
  write_zip(bad,
            {{"main.xml", replaced(xml, "</Record1>", "</Record>")}, {"bindata/data.bin", bin}});
  EXPECT_TRUE(refused("main.xml:"));
  EXPECT_TRUE(refused("malformed XML"));
  write_zip(bad, {{"main.xml", "<?xml version=\"1.0\"?>\n<root/>"}});
  EXPECT_TRUE(refused("main.xml:2:1: the root element is <root>"));
  write_zip(bad, {{"main.xml", replaced(xml, "<SizeX>5</SizeX>", "<SizeX>five</SizeX>")},
                  {"bindata/data.bin", bin}});
  EXPECT_TRUE(refused("<SizeX> 'five' is not a count"));
  write_zip(bad, {{"main.xml", replaced(xml, "<FeatureType>SUR", "<FeatureType>PCL")},
                  {"bindata/data.bin", bin}});
  EXPECT_TRUE(refused("FeatureType 'PCL'"));
  std::string damaged = bin;
  damaged[9] = static_cast<char>(damaged[9] ^ 1);
  write_zip(bad, {{"main.xml", xml}, {"bindata/data.bin", damaged}});
  EXPECT_TRUE(refused("does not match its MD5 checksum"));
  write_zip(bad, {{"main.xml", xml}, {"bindata/data.bin", bin.substr(0, 100)}});
  EXPECT_TRUE(refused("holds 100 bytes; 5 x 4 points of 8 bytes need 160"));
  write_zip(bad, {{"main.xml", xml}, {"bindata/data.bin", bin + "extra"}});
  EXPECT_TRUE(refused("more than the 160 expected"));
  std::string nan_bin = bin;
  const double nan = std::nan("");
  std::memcpy(nan_bin.data() + 8 * 7, &nan, 8);
  const auto s = xml.find("<MD5ChecksumPointData>");
  std::string unchecked = xml;
  unchecked.erase(s, xml.find("</MD5ChecksumPointData>") + 23 - s);
  write_zip(bad, {{"main.xml", unchecked}, {"bindata/data.bin", nan_bin}});
  EXPECT_TRUE(refused("point 7 (column 2, row 1) is not measured (NaN)"));
  EXPECT_NE(test::message_of([&] { (void)read_x3p(scratch("missing.x3p")); }).find("cannot read"),
            std::string::npos);
  fs::remove_all(good.parent_path());
}

}  // namespace
}  // namespace trochomill
