// The cutter model (cutter.hpp): the edge contour of a solid end mill or an insert mill, its
// segments along the edge and the structured grid the force and wear models address.
#include "trochomill/cutter.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

// The contour (see SimTool): corner arc about (R - rc, rc) from the face (angle phi = 0) to
// phi_t = pi - kappa_r, at height h_t = rc (1 - cos phi_t) and radius r_t = R - rc + rc sin
// phi_t; then the main edge, radius r_t - (h - h_t) cot kappa_r.
ToolContour::ToolContour(const SimTool& t)
    : radius_(t.radius_mm),
      rc_(t.corner_radius_mm),
      rcen_(t.radius_mm - t.corner_radius_mm),
      ht_(t.corner_radius_mm * (1 - std::cos(kPi - t.lead_rad))),
      rt_(rcen_ + t.corner_radius_mm * std::sin(kPi - t.lead_rad)),
      tan_lead_(std::tan(t.lead_rad)),
      sin_lead_(std::sin(t.lead_rad)),
      cylindrical_(t.lead_rad >= 0.5 * kPi - 1e-12) {
  flank_ = profile_radius(ht_ + 1e-12);
}

double ToolContour::profile_radius(double h) const {
  if (h < 0) return -1;
  if (h <= ht_ && rc_ > 0) {
    const double dz = rc_ - h;
    return rcen_ + std::sqrt(std::max(0.0, rc_ * rc_ - dz * dz));
  }
  if (cylindrical_) return radius_;
  const double r = rt_ - (h - ht_) / tan_lead_;
  return r > 0 ? r : -1;
}

double ToolContour::edge_sine(double h) const {
  if (h <= ht_ && rc_ > 0) {
    const double c = std::clamp(1 - std::max(0.0, h) / rc_, -1.0, 1.0);
    return std::sqrt(std::max(0.0, 1 - c * c));  // sin phi
  }
  return sin_lead_;
}

std::optional<Interval> ToolContour::heights_reaching(double rho) const {
  if (rho > radius_) return std::nullopt;
  double lo = 0, hi = ht_;
  if (rho > rcen_) {  // on the arc: |rc - h| <= sqrt(rc^2 - q^2)
    const double q = rho - rcen_, sq = std::sqrt(std::max(0.0, rc_ * rc_ - q * q));
    lo = rc_ - sq;
    hi = std::min(ht_, rc_ + sq);
  }
  if (cylindrical_) {
    if (rho <= flank_ || rc_ == 0) hi = std::numeric_limits<double>::infinity();
  } else {
    if (rho <= rt_) hi = std::max(hi, ht_ + (rt_ - rho) * tan_lead_);
  }
  if (!(hi >= lo)) return std::nullopt;
  return Interval{lo, hi};
}

double SimTool::profile_radius(double h) const { return ToolContour(*this).profile_radius(h); }

double SimTool::edge_sine(double h) const { return ToolContour(*this).edge_sine(h); }

std::optional<Interval> SimTool::heights_reaching(double rho) const {
  return ToolContour(*this).heights_reaching(rho);
}

double SimTool::widest_height(double h0, double h1) const {
  // The contour is widest at h = rc (the arc's outermost point; from there up on a
  // cylindrical flank).
  return std::clamp(corner_radius_mm, h0, h1);
}

double SimTool::edge_length_at(double h) const {
  const double rc = corner_radius_mm;
  const double phit = kPi - lead_rad, ht = rc * (1 - std::cos(phit));
  h = std::max(0.0, h);
  if (h <= ht && rc > 0) return rc * std::acos(std::clamp(1 - h / rc, -1.0, 1.0));
  return rc * phit + (h - ht) / std::sin(lead_rad);
}

double SimTool::height_at_length(double s) const {
  const double rc = corner_radius_mm;
  const double phit = kPi - lead_rad, ht = rc * (1 - std::cos(phit));
  s = std::max(0.0, s);
  if (s <= rc * phit && rc > 0) return rc * (1 - std::cos(s / rc));
  return ht + (s - rc * phit) * std::sin(lead_rad);
}

int SimTool::segments() const {
  return std::max(1,
                  static_cast<int>(std::ceil(edge_length_at(flute_length_mm) / segment_mm - 1e-9)));
}

int SimTool::segment_at(double h) const {
  return std::clamp(static_cast<int>(edge_length_at(h) / segment_mm), 0, segments() - 1);
}

EdgeGrid edge_grid(const SimTool& tool, double band_mm) {
  if (!(band_mm > 0))
    throw InputError(fmt::format("edge grid band must be > 0 mm, got {}", band_mm));
  EdgeGrid g;
  g.segments = tool.segments();
  g.sub_segments = std::max(1, tool.sub_segments);
  g.band_mm = band_mm;
  const double total = tool.edge_length_at(tool.flute_length_mm);
  for (int k = 0; k < g.segments; ++k) {
    const double s0 = k * tool.segment_mm, s1 = std::min(total, (k + 1) * tool.segment_mm);
    const double sm = 0.5 * (s0 + s1), h = tool.height_at_length(sm);
    // The contour's outward normal in the (radial, axial) plane: (sin phi, -cos phi) on the
    // corner arc, (sin kappa_r, cos kappa_r) on the main edge.
    const double rc = tool.corner_radius_mm, phit = kPi - tool.lead_rad;
    double nr = std::sin(tool.lead_rad), nz = std::cos(tool.lead_rad);
    if (rc > 0 && sm <= rc * phit) nr = std::sin(sm / rc), nz = -std::cos(sm / rc);
    for (int t = 0; t < g.sub_segments; ++t) {
      EdgeCell c;
      c.kappa = k;
      c.tau = t;
      c.s_mm = sm;
      c.h_mm = h;
      c.r_mm = tool.profile_radius(h);
      c.width_mm = s1 - s0;
      c.depth_mm = (t + 0.5) * band_mm / g.sub_segments;
      c.normal = {nr, 0.0, nz};
      c.facet = {0.0, 1.0, 0.0};  // the rake face of a sharp edge (zero rake)
      c.proj_mm = t * band_mm / g.sub_segments;
      c.proj_end_mm = (t + 1) * band_mm / g.sub_segments;
      c.para_mm = band_mm / g.sub_segments;
      g.cells.push_back(c);
    }
  }
  return g;
}

SimTool sim_tool(const Job& job, const SimSettings& s) {
  SimTool t;
  t.radius_mm = job.tool.radius_mm();
  t.corner_radius_mm = job.tool.corner_radius_mm;
  // Without a flute length the edges reach the top of the slot or pocket (depth plus 1 mm).
  t.flute_length_mm = job.tool.flute_length_mm > 0
                          ? job.tool.flute_length_mm
                          : std::max(job.slot.depth_mm, job.pocket.depth_mm) + 1.0;
  t.helix_rad = deg_to_rad(job.tool.helix_angle_deg);
  const double phase = deg_to_rad(job.tool.runout_phase_deg);
  for (const double a : job.tool.tooth_angles_deg) {
    const double ar = deg_to_rad(a);
    t.tooth_angle_rad.push_back(ar);
    // Runout as an axis offset e at `phase` from tooth 0: tooth k's cutting radius grows by
    // e cos(angle_k - phase) (first order in e / R); axial runout lowers its tip by
    // e_ax cos(angle_k - phase): the tooth at the phase cuts the largest radius and sits
    // lowest (docs/models.md section 4, as the analysis's tooth tracks).
    t.radial_offset_mm.push_back(job.tool.runout_radial_mm * std::cos(ar - phase));
    t.axial_offset_mm.push_back(-job.tool.runout_axial_mm * std::cos(ar - phase));
  }
  const double w = rpm_to_rad_per_s(spindle_speed_rpm(job));
  t.omega_rad_per_s = job.cutting.spindle_direction == SpindleDirection::cw ? -w : w;
  t.lead_rad = deg_to_rad(job.tool.lead_angle_deg);
  for (std::size_t k = 0; k < job.tool.insert_radial_mm.size() && k < t.radial_offset_mm.size();
       ++k) {
    t.radial_offset_mm[k] += job.tool.insert_radial_mm[k];
  }
  for (std::size_t k = 0; k < job.tool.insert_axial_mm.size() && k < t.axial_offset_mm.size();
       ++k) {
    t.axial_offset_mm[k] -= job.tool.insert_axial_mm[k];  // positive seating: lower
  }
  t.segment_mm = s.segment_mm;
  t.sub_segments = s.sub_segments;
  return t;
}

}  // namespace trochomill
