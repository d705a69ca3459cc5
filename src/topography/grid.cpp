// Sampling a mesh's visible topography into the edge's structured grid (topography.hpp;
// docs/models.md section 13).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "contour.hpp"
#include "trochomill/error.hpp"
#include "trochomill/topography.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

// The along-edge scale for the RBF's domain (s, L theta): from (s, theta) points sorted by s
// then theta; 1 for scattered data.
double section_scale(const std::vector<std::array<double, 2>>& sorted, double L) {
  std::vector<std::size_t> first;  // each section's first point
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    if (i == 0 || sorted[i][0] - sorted[i - 1][0] > 1e-6) first.push_back(i);
  }
  if (first.size() < 2 || first.size() * 4 > sorted.size()) return 1.0;
  std::vector<double> ds, dv;
  for (std::size_t k = 0; k + 1 < first.size(); ++k) {
    ds.push_back(sorted[first[k + 1]][0] - sorted[first[k]][0]);
    for (std::size_t i = first[k] + 1; i < first[k + 1]; ++i) {
      dv.push_back(sorted[i][1] - sorted[i - 1][1]);  // theta, sorted within the section
    }
  }
  if (dv.empty()) return 1.0;
  const auto median = [](std::vector<double>& v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double gap = median(ds), along = L * median(dv);
  return gap > 0 ? std::clamp(along / gap, 1e-3, 1.0) : 1.0;
}

}  // namespace

EdgeGrid sample_topography(const Mesh& mesh, const SimTool& tool, double band_mm,
                           EdgeTopography* info) {
  if (!(band_mm > 0))
    throw InputError(fmt::format("topography band must be > 0 mm, got {}", band_mm));
  EdgeGrid g = edge_grid(tool, band_mm);
  const double L = std::max(0.5, 2 * band_mm);  // polar centre inward and behind the edge
  // Facets visible along the cutting direction: their outward normal has no component
  // against it (edge-on facets kept, within 0.5 degrees: a wear land is parallel to v_c).
  const double tol = std::sin(0.5 * kPi / 180);
  std::vector<char> keep(mesh.vertices.size(), 0);
  std::size_t kept = 0;
  for (const auto& t : mesh.triangles) {
    const auto n = facet_of(mesh, t).n;
    const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), ny = n[1];
    if (!(nn > 0) || ny / nn < -tol) continue;
    ++kept;
    keep[t[0]] = keep[t[1]] = keep[t[2]] = 1;
  }
  // Their points in section coordinates: u along the edge, v = L theta about the polar
  // centre O = (p, q) = (-L, -L), value rho = |X - O|.
  const double total = tool.edge_length_at(tool.flute_length_mm);
  std::map<std::pair<long long, long long>, std::size_t> seen;  // joins coincident points
  std::vector<std::array<double, 2>> pts;
  std::vector<double> vals;
  double smin = 1e300, smax = -1e300;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (!keep[i]) continue;
    const auto& x = mesh.vertices[i];
    const ContourPoint c = project_on_contour(tool, x[0], x[2]);
    if (c.s < -1e-9 || c.s > total + 1e-9) continue;
    const double p = (x[0] - c.r) * c.nr + (x[2] - c.h) * c.nz, q = x[1];
    if (!(p > -0.9 * L && q > -0.9 * L && p < L && q < L)) continue;  // near the edge only
    const double th = std::atan2(q + L, p + L), rho = std::hypot(p + L, q + L);
    const auto key = std::make_pair(std::llround(c.s * 1e7), std::llround(L * th * 1e7));
    if (!seen.emplace(key, pts.size()).second) continue;
    pts.push_back({c.s, L * th});
    vals.push_back(rho);
    smin = std::min(smin, c.s), smax = std::max(smax, c.s);
  }
  if (pts.size() < 16) {
    throw InputError(fmt::format(
        "topography: {} of {} facets face the cutting direction (+y) near the edge, {} points; "
        "is the mesh in the tooth frame (x radial, y cutting direction, z axial, mm)?",
        kept, mesh.triangles.size(), pts.size()));
  }
  if (info != nullptr) {
    info->centre_mm = L;
    info->points = pts.size();
    info->facets_kept = kept;
    info->facets_total = mesh.triangles.size();
    info->s_min_mm = smin, info->s_max_mm = smax;
  }
  // theta range of the data near each segment (0.1 mm or a segment along the edge).
  std::vector<std::array<double, 2>> sorted(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) sorted[i] = {pts[i][0], pts[i][1] / L};
  std::sort(sorted.begin(), sorted.end());
  // Meshes built (or scanned) in sections across the edge hold many points per section and
  // few sections; the cubic RBF sags between sections spaced far wider than the points along
  // them (2 um on a flat wear land between sections 0.05 mm apart, against 0.03 um with the
  // spacings matched). So s is scaled by (spacing along a section) / (spacing of sections)
  // when the points come in sections (at most a quarter as many distinct s as points).
  const double s_scale = section_scale(sorted, L);
  if (info != nullptr) info->s_scale = s_scale;
  for (auto& q : pts) q[0] *= s_scale;
  const CubicRbf rbf(std::move(pts), std::move(vals));

  const int tau = g.sub_segments;
  for (int k = 0; k < g.segments; ++k) {
    const double sk = g.at(k, 0).s_mm;
    if (sk < smin || sk > smax) continue;  // beyond the mesh: the sharp edge stays
    const double win = std::max(0.1, tool.segment_mm);
    auto lo = std::lower_bound(sorted.begin(), sorted.end(), std::array<double, 2>{sk - win, -1e9});
    auto hi = std::upper_bound(sorted.begin(), sorted.end(), std::array<double, 2>{sk + win, 1e9});
    double th0 = 1e300, th1 = -1e300;
    for (auto it = lo; it != hi; ++it) th0 = std::min(th0, (*it)[1]), th1 = std::max(th1, (*it)[1]);
    if (!(th1 > th0)) continue;
    // The profile at sk, finely in theta.
    const int m = 2000;
    std::vector<double> pp(m + 1), qq(m + 1);
    double pmax = -1e300;
    for (int i = 0; i <= m; ++i) {
      const double th = th0 + (th1 - th0) * i / m, rho = rbf(sk * s_scale, L * th);
      pp[static_cast<std::size_t>(i)] = -L + rho * std::cos(th);
      qq[static_cast<std::size_t>(i)] = -L + rho * std::sin(th);
      pmax = std::max(pmax, pp[static_cast<std::size_t>(i)]);
    }
    // The outer edge: the first point within 0.1 um of the outermost (the back end of a land).
    int i0 = 0;
    while (i0 < m && pp[static_cast<std::size_t>(i0)] < pmax - 1e-4) ++i0;
    // Arc length, depth and normal from there inward until the band is crossed.
    std::vector<double> para{0.0}, proj{pmax - pp[static_cast<std::size_t>(i0)]};
    std::vector<std::array<double, 2>> nrm;
    for (int i = i0 + 1; i <= m; ++i) {
      const auto a = static_cast<std::size_t>(i - 1), b = static_cast<std::size_t>(i);
      const double dp = pp[b] - pp[a], dq = qq[b] - qq[a], ds = std::hypot(dp, dq);
      if (!(ds > 0)) continue;
      para.push_back(para.back() + ds);
      proj.push_back(pmax - pp[b]);
      nrm.push_back({dq / ds, -dp / ds});  // the tangent turned outward
      if (proj.back() >= band_mm) break;
    }
    if (nrm.empty()) continue;
    const double total_para = para.back();
    const ContourPoint c = contour_at(tool, sk);
    std::size_t e = 0;
    for (int t = 0; t < tau; ++t) {
      const double a = total_para * t / tau, b = total_para * (t + 1) / tau;
      const auto interp = [&](double sp) {
        const auto it = std::upper_bound(para.begin(), para.end(), sp);
        const std::size_t j = std::clamp<std::size_t>(static_cast<std::size_t>(it - para.begin()),
                                                      1, para.size() - 1);
        const double f = (sp - para[j - 1]) / std::max(1e-300, para[j] - para[j - 1]);
        return proj[j - 1] + std::clamp(f, 0.0, 1.0) * (proj[j] - proj[j - 1]);
      };
      double np = 0, nq = 0;
      while (e < nrm.size() && para[e] < b) {
        const double w = std::min(para[e + 1], b) - std::max(para[e], a);
        if (w > 0) np += w * nrm[e][0], nq += w * nrm[e][1];
        if (para[e + 1] > b) break;
        ++e;
      }
      const double nn = std::hypot(np, nq);
      if (nn > 0) np /= nn, nq /= nn;
      EdgeCell& cell = g.cells[static_cast<std::size_t>(k * tau + t)];
      cell.facet = {np * c.nr, nq, np * c.nz};
      cell.proj_mm = t == 0 ? 0.0 : interp(a);
      cell.proj_end_mm = interp(b);
      cell.depth_mm = 0.5 * (cell.proj_mm + cell.proj_end_mm);
      cell.para_mm = b - a;
    }
  }
  return g;
}

}  // namespace trochomill
