// sin and cos together, without libm's argument reduction (not installed).
#pragma once

#include <array>
#include <cfloat>
#include <cmath>
#include <cstddef>

namespace trochomill::detail {

struct SinCos {
  double s, c;
};

/// sin t and cos t from a table of one turn at 64 anchors and the Taylor series of the offset
/// from the nearest anchor (|d| <= pi / 64: the sine to d^9, the cosine to d^10, each
/// truncation below 1e-17 relative), the offset taken in two parts so a large t loses no
/// digits: the absolute error against libm's is at most 2.2e-16 for |t| up to 2e7 rad
/// (measured on 1e7 random angles per range; a spindle's angle after ten minutes at 30,000 rpm
/// is 1.9e6 rad): one or two ulps of values near 1, more ulps (not more error) near the zeros
/// of sin and cos, and sin(-0) is +0. libm's beyond 2e7 rad. About five times faster than
/// libm's sincos, which the model loops call tens of times a point. Needs double arithmetic
/// without excess precision (the rounding below; checked at compile time).
static_assert(FLT_EVAL_METHOD == 0, "SinCosTable rounds by adding 1.5 * 2^52 in double");

class SinCosTable {
 public:
  SinCosTable() {
    // The anchors in long double (x87's 64-bit mantissa on x86-64), each then rounded once.
    constexpr long double kPiL = 3.14159265358979323846264338327950288L;
    for (int m = 0; m < kN; ++m) {
      const long double a = m * kPiL / (kN / 2);
      s_[static_cast<std::size_t>(m)] = static_cast<double>(std::sin(a));
      c_[static_cast<std::size_t>(m)] = static_cast<double>(std::cos(a));
    }
  }
  [[nodiscard]] SinCos operator()(double t) const {
    if (!(std::abs(t) <= 2e7)) return {std::sin(t), std::cos(t)};  // (and NaN, infinities)
    // Round to the nearest whole number by the 1.5 * 2^52 trick (no libm call on baseline
    // x86-64; |t * kInvStep| < 2^51).
    const double mf = (t * kInvStep + 0x1.8p52) - 0x1.8p52;
    // The offset in two parts (Cody and Waite): mf * kStepHi is exact for |mf| < 2^28.
    const double d = (t - mf * kStepHi) - mf * kStepLo, d2 = d * d;
    // Coefficients 1 / k! (alternating), Horner in d^2.
    const double sd =
        d + d * d2 * (-1.0 / 6 + d2 * (1.0 / 120 + d2 * (-1.0 / 5040 + d2 * (1.0 / 362880))));
    const double cd =
        1 + d2 * (-0.5 +
                  d2 * (1.0 / 24 + d2 * (-1.0 / 720 + d2 * (1.0 / 40320 + d2 * (-1.0 / 3628800)))));
    const auto i = static_cast<std::size_t>(static_cast<long>(mf) & (kN - 1));
    return {s_[i] * cd + c_[i] * sd, c_[i] * cd - s_[i] * sd};
  }

 private:
  static constexpr int kN = 64;
  static constexpr double kStepHi = 0x1.921fb5p-4;          // kStep to 25 bits
  static constexpr double kStepLo = 0x1.110b4611a6263p-30;  // pi / 32 - kStepHi
  static constexpr double kInvStep = kN / 6.283185307179586476925286766559;
  std::array<double, kN> s_{}, c_{};
};

/// The one table (built on first use).
inline const SinCosTable& sincos_table() {
  static const SinCosTable t;
  return t;
}

}  // namespace trochomill::detail
