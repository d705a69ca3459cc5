// Biarc and chord fits of a path's curve segments (gcode.hpp): the segment as a PlanarCurve
// for the geometry module's fitters.
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill {
namespace {

// A curve segment in its plane z = const, run from u0 to u1.
class SegmentCurve final : public PlanarCurve {
 public:
  explicit SegmentCurve(const Segment& s) : s_(s) {}
  [[nodiscard]] Vec3 point(double u) const override { return s_.point_u(u); }
  [[nodiscard]] Vec3 unit_tangent(double u) const override {
    Vec3 d = s_.derivative_u(u) * (s_.u1() >= s_.u0() ? 1.0 : -1.0);
    d.z() = 0;
    const double n = d.norm();
    return n > 0 ? Vec3(d / n) : Vec3::Zero();
  }

 private:
  const Segment& s_;
};

// Initial pieces: at most a quarter turn each, so every biarc spans a gentle piece.
int initial_pieces(const Segment& c) {
  return std::max(1, static_cast<int>(std::ceil(std::abs(c.u1() - c.u0()) / (0.5 * M_PI))));
}

}  // namespace

std::vector<FitArc> fit_biarcs(const Segment& curve, double tolerance_mm) {
  if (!(tolerance_mm > 0)) throw InputError("arc tolerance must be > 0 mm");
  if (curve.kind() != Segment::Kind::curve || !curve.is_flat_xy()) {
    throw Error("fit_biarcs needs a curve in a plane z = const");
  }
  // Exact end points: the last arc ends where the curve ends.
  return fit_biarcs(SegmentCurve(curve), curve.u0(), curve.u1(), initial_pieces(curve),
                    tolerance_mm);
}

std::vector<Vec3> fit_chords(const Segment& curve, double tolerance_mm) {
  if (!(tolerance_mm > 0)) throw InputError("arc tolerance must be > 0 mm");
  if (curve.kind() == Segment::Kind::line) return {curve.end()};
  return fit_chords(SegmentCurve(curve), curve.u0(), curve.u1(), initial_pieces(curve),
                    tolerance_mm);
}

}  // namespace trochomill
