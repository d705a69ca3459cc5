// The HTML report: the results of a job gathered into one JSON document (series decimated for
// display, keeping every extreme; maps and meshes as base64 16-bit grids) and one page that
// embeds it with the bundled scripts (web_assets.hpp). The page draws everything in the browser
// (web/src/report.js); nothing here draws.
#include <fmt/format.h>
#include <nettle/base64.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>

#include "trochomill/error.hpp"
#include "trochomill/geometry/drawing.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"
#include "trochomill/version.hpp"
#include "web_assets.hpp"

namespace trochomill {
namespace {

using nlohmann::json;

constexpr std::size_t kPathSamples = 6000;  // the path drawn and scrubbed (uniform in time)
constexpr std::size_t kMapColumns = 1500;   // heat maps: time bins
constexpr double kRad = 180.0 / 3.14159265358979323846;

// Six significant digits: what a plot can show, and a third of the text of full precision.
// Not finite: null (a gap in the plot).
json number(double v) {
  if (!std::isfinite(v)) return nullptr;
  return std::strtod(fmt::format("{:.6g}", v).c_str(), nullptr);
}

json pick(const std::vector<double>& v, const std::vector<std::size_t>& idx, double scale = 1,
          double offset = 0) {
  json a = json::array();
  for (const std::size_t i : idx) a.push_back(number(v[i] * scale + offset));
  return a;
}

std::vector<std::size_t> all_indices(std::size_t n) {
  std::vector<std::size_t> idx(n);
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  return idx;
}

// Measurements of the run itself (wall times, rates, the process's peak memory, the memory
// estimate that starts from the process's resident size) differ from run to run: a report
// leaves them out, so the same command writes the same page.
json without_measurements(json j) {
  for (auto it = j.begin(); it != j.end();) it = is_run_measurement(it.key()) ? j.erase(it) : ++it;
  return j;
}

// A decimated block of series sharing their x: `cols` named columns, the first the x.
struct Column {
  std::string name;
  const std::vector<double>* values;
  double scale = 1;
};
json series_block(const std::vector<Column>& cols, std::size_t first, std::size_t last) {
  std::vector<std::vector<double>> sub;
  sub.reserve(cols.size());
  for (const Column& c : cols) {
    sub.emplace_back(c.values->begin() + static_cast<std::ptrdiff_t>(first),
                     c.values->begin() + static_cast<std::ptrdiff_t>(last));
  }
  std::vector<const std::vector<double>*> ys;
  for (std::size_t k = 1; k < sub.size(); ++k) ys.push_back(&sub[k]);
  const auto idx = decimation_indices(last - first, ys, report_columns);
  json out = json::object();
  for (std::size_t k = 0; k < cols.size(); ++k)
    out[cols[k].name] = pick(sub[k], idx, cols[k].scale);
  out["samples"] = last - first;
  out["shown"] = idx.size();
  return out;
}
json series_block(const std::vector<Column>& cols) {
  return series_block(cols, 0, cols.front().values->size());
}

std::string base64(const std::vector<std::uint8_t>& bytes) {
  std::string out(BASE64_ENCODE_RAW_LENGTH(bytes.size()), '\0');
  base64_encode_raw(out.data(), bytes.size(), bytes.data());
  return out;
}

// A grid (row-major, rows x columns; NaN allowed) as 16-bit levels between its finite minimum
// and maximum, 65535 for NaN: a quarter of the text of decimal numbers, resolution 1/65534 of
// the range.
json grid16(const std::vector<double>& v, std::size_t columns, std::size_t rows) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const double x : v) {
    if (std::isfinite(x)) lo = std::min(lo, x), hi = std::max(hi, x);
  }
  if (!(lo <= hi)) lo = hi = 0;
  const double span = hi > lo ? hi - lo : 1.0;
  std::vector<std::uint8_t> bytes(2 * v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    std::uint16_t q = 65535;
    if (std::isfinite(v[i]))
      q = static_cast<std::uint16_t>(std::lround((v[i] - lo) / span * 65534));
    bytes[2 * i] = static_cast<std::uint8_t>(q & 0xff);
    bytes[2 * i + 1] = static_cast<std::uint8_t>(q >> 8);
  }
  return {{"columns", columns}, {"rows", rows},    {"min", number(lo)},
          {"max", number(hi)},  {"levels", 65534}, {"data", base64(bytes)}};
}

// Bins of `n` items into at most `bins` runs: the start of run k.
std::size_t bin_start(std::size_t k, std::size_t n, std::size_t bins) { return k * n / bins; }

json path_part(const ReportData& d) {
  const ToolPath& p = d.path;
  const double T = p.duration_s();
  const PathSamples s = sample_by_time(p, std::max(T / static_cast<double>(kPathSamples), 1e-6));
  // Rapids as [first, last] sample ranges.
  json rapid = json::array();
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (p.segments()[s.segment[i]].motion() != Motion::rapid) continue;
    std::size_t j = i;
    while (j + 1 < s.size() && p.segments()[s.segment[j + 1]].motion() == Motion::rapid) ++j;
    rapid.push_back({i, j});
    i = j;
  }
  const auto idx = all_indices(s.size());
  const SlotGeometry g = slot_geometry(d.job);
  // The slot's outline: the rectangle of a straight slot; the region within W/2 of a curved
  // one's centreline (its boundaries, each closed, null between them), and its box.
  json outline_x = json::array(), outline_y = json::array();
  double x_min = -0.5 * d.job.slot.width_mm, x_max = 0.5 * d.job.slot.width_mm, y_min = 0.0,
         y_max = d.job.slot.length_mm;
  const bool pocket = d.job.pocket.defined();
  if (d.job.slot.curved() || pocket) {
    Box3 box;
    // A pocket: its walls and islands as drawn; a curved slot: its walls.
    std::vector<Contour> walls;
    if (pocket) {
      for (const DrawnContour& c : *d.job.pocket.boundary_contours) walls.push_back(c.contour);
      for (const DrawnContour& c : *d.job.pocket.island_contours) walls.push_back(c.contour);
    } else {
      walls = offset_curve(d.job.slot.centreline->contour, 0.5 * d.job.slot.width_mm, 0.01);
    }
    for (const Contour& c : walls) {
      const std::vector<Vec2> pts = c.points(0.01);
      if (!outline_x.empty()) {
        outline_x.push_back(nullptr);
        outline_y.push_back(nullptr);
      }
      for (std::size_t k = 0; k <= pts.size() && !pts.empty(); ++k) {
        const Vec2& q = pts[k % pts.size()];
        outline_x.push_back(number(q.x()));
        outline_y.push_back(number(q.y()));
        box.extend(Vec3(q.x(), q.y(), 0));
      }
    }
    x_min = box.lo.x();
    x_max = box.hi.x();
    y_min = box.lo.y();
    y_max = box.hi.y();
  } else {
    outline_x = {number(x_min), number(x_max), number(x_max), number(x_min), number(x_min)};
    outline_y = {number(y_min), number(y_min), number(y_max), number(y_max), number(y_min)};
  }
  // The drawing under a curved slot: every contour of the other layers (the part's walls,
  // islands, holes), as chords within 0.01 mm, null between them. A drawing whose other layers
  // cannot be read (a gap, a branch) leaves them out with a note; the slot was read alone.
  // A pocket's [stock] mesh: where it stands at the first level (its plan view from that level
  // up: a cored hole, a step show as holes and edges in it).
  json stock = nullptr;
  if (pocket && d.job.stock_mesh && d.job.stock_max_mm) {
    const double top = (*d.job.stock_max_mm)[2];
    const double z1 = -d.job.pocket.depth_mm / pocket_level_count(d.job.pocket);
    json sx = json::array(), sy = json::array();
    for (const Contour& c : mesh_plan_region(*d.job.stock_mesh, std::min(z1, top), top)) {
      const std::vector<Vec2> pts = c.points(0.01);
      if (!sx.empty()) {
        sx.push_back(nullptr);
        sy.push_back(nullptr);
      }
      for (std::size_t k = 0; k <= pts.size() && !pts.empty(); ++k) {
        sx.push_back(number(pts[k % pts.size()].x()));
        sy.push_back(number(pts[k % pts.size()].y()));
      }
    }
    stock = {{"x_mm", sx}, {"y_mm", sy}, {"z_mm", number(z1)}, {"file", d.job.stock_mesh_file}};
  }
  json drawing_x = json::array(), drawing_y = json::array(), drawing_layers = json::array();
  json drawing_note = nullptr;
  if ((d.job.slot.curved() || pocket) && !d.job.geometry.path.empty()) {
    DrawingOptions o;
    o.join_tolerance_mm = d.job.geometry.join_tolerance_mm;
    o.arc_tolerance_mm = std::max(d.job.machine.arc_tolerance_mm, 0.01);
    try {
      const Drawing drawing = read_drawing(d.job.geometry.path, o);
      for (const DrawnContour& c : drawing.contours) {
        if (pocket ? c.layer == d.job.pocket.boundary || c.layer == d.job.pocket.islands
                   : c.layer == d.job.slot.along) {
          continue;
        }
        if (std::find(drawing_layers.begin(), drawing_layers.end(), c.layer) ==
            drawing_layers.end()) {
          drawing_layers.push_back(c.layer);
        }
        const std::vector<Vec2> pts = c.contour.points(0.01);
        if (!drawing_x.empty()) {
          drawing_x.push_back(nullptr);
          drawing_y.push_back(nullptr);
        }
        for (std::size_t k = 0; k < pts.size() + (c.contour.closed ? 1 : 0); ++k) {
          const Vec2& q = pts[k % pts.size()];
          drawing_x.push_back(number(q.x()));
          drawing_y.push_back(number(q.y()));
          x_min = std::min(x_min, q.x()), x_max = std::max(x_max, q.x());
          y_min = std::min(y_min, q.y()), y_max = std::max(y_max, q.y());
        }
      }
    } catch (const InputError& e) {
      drawing_note = fmt::format("the drawing's other layers are not shown: {}", e.what());
    }
  }
  // The samples are uniform in time but the last (at the end): t_i = i dt, the last T.
  json out = {
      {"dt_s", s.size() > 1 ? number(s.t_s[1] - s.t_s[0]) : json(0.0)},
      {"samples", s.size()},
      {"x_mm", pick(s.x_mm, idx)},
      {"y_mm", pick(s.y_mm, idx)},
      {"z_mm", pick(s.z_mm, idx)},
      {"rapid", rapid},
      {"duration_s", number(T)},
      {"tool_radius_mm", number(g.tool_radius_mm)},
      {"teeth", d.job.tool.teeth},
      {"slot",
       {{"x_min_mm", number(x_min)},
        {"x_max_mm", number(x_max)},
        {"y_min_mm", number(y_min)},
        {"y_max_mm", number(y_max)},
        {"width_mm", number(d.job.slot.width_mm)},
        {"length_mm", number(d.job.slot.length_mm)},
        {"along", d.job.slot.along},
        {"depth_mm", number(d.job.slot.depth_mm)}}},
      {"pocket", pocket ? json{{"boundary", d.job.pocket.boundary},
                               {"islands", d.job.pocket.islands},
                               {"depth_mm", number(d.job.pocket.depth_mm)},
                               {"max_engagement_deg", number(d.job.pocket.max_engagement_deg)}}
                        : json(nullptr)},
      {"outline", {{"x_mm", outline_x}, {"y_mm", outline_y}}},
      {"stock", stock},
      {"drawing",
       {{"x_mm", drawing_x},
        {"y_mm", drawing_y},
        {"layers", drawing_layers},
        {"note", drawing_note}}},
      {"cycle_from_s", number(d.metrics.cycle_start_s)},
      {"cycle_to_s", number(d.metrics.cycle_start_s + d.metrics.cycle_time_s)},
      {"periodic", d.metrics.periodic}};
  out["entry_to_s"] = p.cycles().empty() ? nullptr : number(p.cycles().front().start_time_s);
  return out;
}

json engagement_part(const ReportData& d) {
  const EngagementSeries& e = d.metrics.series;
  const std::size_t n = e.samples.size();
  std::vector<double> eng(n), h(n), teeth(n);
  for (std::size_t i = 0; i < n; ++i) {
    eng[i] = e.engagement_angle_rad[i] * kRad;
    h[i] = radial_chip_mm(e, i, e.tool_radius_mm);
    teeth[i] = e.teeth_in_cut[i];
  }
  const std::vector<Column> cols = {{"t_s", &e.samples.t_s},
                                    {"engagement_deg", &eng},
                                    {"h_max_mm", &h},
                                    {"teeth_in_cut", &teeth}};
  json out = {{"program", series_block(cols)}};
  // The steady cycle (or window), its time from the cycle's start.
  const double t0 = d.metrics.cycle_start_s, t1 = t0 + d.metrics.cycle_time_s;
  const auto first = static_cast<std::size_t>(
      std::lower_bound(e.samples.t_s.begin(), e.samples.t_s.end(), t0) - e.samples.t_s.begin());
  const auto last = static_cast<std::size_t>(
      std::upper_bound(e.samples.t_s.begin(), e.samples.t_s.end(), t1) - e.samples.t_s.begin());
  if (last > first + 1) {
    std::vector<double> rel(e.samples.t_s.begin() + static_cast<std::ptrdiff_t>(first),
                            e.samples.t_s.begin() + static_cast<std::ptrdiff_t>(last));
    for (double& t : rel) t -= t0;
    std::vector<double> sub_eng(eng.begin() + static_cast<std::ptrdiff_t>(first),
                                eng.begin() + static_cast<std::ptrdiff_t>(last));
    std::vector<double> sub_h(h.begin() + static_cast<std::ptrdiff_t>(first),
                              h.begin() + static_cast<std::ptrdiff_t>(last));
    std::vector<double> sub_teeth(teeth.begin() + static_cast<std::ptrdiff_t>(first),
                                  teeth.begin() + static_cast<std::ptrdiff_t>(last));
    out["cycle"] = series_block({{"t_s", &rel},
                                 {"engagement_deg", &sub_eng},
                                 {"h_max_mm", &sub_h},
                                 {"teeth_in_cut", &sub_teeth}});
    const auto k =
        static_cast<std::size_t>(std::max_element(sub_h.begin(), sub_h.end()) - sub_h.begin());
    out["cycle_h_max"] = {{"t_s", number(rel[k])}, {"h_mm", number(sub_h[k])}};
  }
  out["program_h_max"] = {{"t_s", number(d.metrics.t_h_max_slot_s)},
                          {"h_mm", number(d.metrics.h_max_slot_mm)}};
  return out;
}

json wall_profile(const WallProfile& w) {
  const auto idx = all_indices(w.y_mm.size());
  return {{"y_mm", pick(w.y_mm, idx)},
          {"x_mm", pick(w.x_mm, idx)},
          {"waviness_mm", number(w.waviness_mm)}};
}

json texture_profile(const ProfileTexture& t) {
  const std::size_t n = t.roughness_profile_mm.size();
  std::vector<double> y(n), primary(n);
  for (std::size_t i = 0; i < n; ++i) {
    y[i] = t.profile_start_mm + static_cast<double>(i) * t.profile_dx_mm;
    primary[i] = t.roughness_profile_mm[i] + t.waviness_profile_mm[i];
  }
  json out = series_block(
      {{"y_mm", &y}, {"primary_mm", &primary}, {"mean_line_mm", &t.waviness_profile_mm}});
  out["cutoff_mm"] = number(t.cutoff_mm);
  out["cutoff_source"] = t.cutoff_source;
  out["ra_mm"] = number(t.roughness.ra_mm);
  out["rz_mm"] = number(t.roughness.rz_mm);
  out["wt_mm"] = number(t.wt_mm);
  return out;
}

json walls_part(const ReportData& d) {
  const ProcessMetrics& m = d.metrics;
  json out = {
      {"path",
       {{"left", wall_profile(m.walls_path.left)}, {"right", wall_profile(m.walls_path.right)}}},
      {"tooth",
       {{"left", wall_profile(m.walls_tooth.left)}, {"right", wall_profile(m.walls_tooth.right)}}}};
  const auto idx = all_indices(m.imprint.x_mm.size());
  out["imprint"] = {{"x_mm", pick(m.imprint.x_mm, idx)},
                    {"crossings_per_mm", pick(m.imprint.crossings_per_mm, idx)}};
  if (m.texture_left && !m.texture_left->roughness_profile_mm.empty()) {
    out["texture_left"] = texture_profile(*m.texture_left);
  }
  if (m.texture_right && !m.texture_right->roughness_profile_mm.empty()) {
    out["texture_right"] = texture_profile(*m.texture_right);
  }
  if (m.texture_floor[1] && !m.texture_floor[1]->roughness_profile_mm.empty()) {
    out["texture_floor"] = texture_profile(*m.texture_floor[1]);
  }
  return out;
}

json mechanism_curve_part(const MechanismCurve& c) {
  const std::size_t n = c.theta_rad.size();
  std::vector<double> theta(n), psi(n), gamma(n), kappa(n), zone(n);
  for (std::size_t i = 0; i < n; ++i) {
    theta[i] = c.theta_rad[i] * kRad;
    psi[i] = c.psi_rad[i] * kRad;
    gamma[i] = c.gamma_k_rad[i] * kRad;
    kappa[i] = c.kappa_rad[i] * kRad;
    zone[i] = c.zone[i];
  }
  json out = series_block({{"theta_deg", &theta},
                           {"t_s", &c.t_s},
                           {"h_mm", &c.h_mm},
                           {"psi_deg", &psi},
                           {"gamma_k_deg", &gamma},
                           {"kappa_deg", &kappa},
                           {"k_re_pct", &c.k_re_pct},
                           {"k_re_wear_pct", &c.k_re_wear_pct},
                           {"zone", &zone}});
  out["model"] = c.model == ChipModel::exact ? "exact" : "pivkin2025";
  out["edge_radius_mm"] = number(c.edge_radius_mm);
  out["cycle_time_s"] = number(c.cycle_time_s);
  return out;
}

json mechanism_part(const ReportData& d) {
  const ReportMechanism& r = *d.mechanism;
  const MechanismSettings& st = d.job.mechanism;
  json summary = json::parse(mechanism_json(d.job, st, r.curve, r.zones, r.use_wear));
  for (const char* k : {"theta_deg", "h_mm", "k_re_pct", "zone"}) summary.erase(k);  // in "curve"
  json out = {{"summary", summary},
              {"curve", mechanism_curve_part(r.curve)},
              {"use_wear", r.use_wear},
              {"thresholds",
               {{"czi_max_pct", st.thresholds.czi_max_pct},
                {"czii_max_pct", st.thresholds.czii_max_pct},
                {"transition_pct", st.thresholds.transition_pct}}}};
  if (r.other) out["other"] = mechanism_curve_part(*r.other);
  return out;
}

json force_series_part(const ForceSeries& s) {
  const std::size_t n = s.t_s.size();
  std::vector<double> fr(n);
  for (std::size_t i = 0; i < n; ++i) fr[i] = std::hypot(s.fx_n[i], s.fy_n[i], s.fz_n[i]);
  return series_block({{"t_s", &s.t_s},
                       {"f_x_n", &s.fx_n},
                       {"f_y_n", &s.fy_n},
                       {"f_z_n", &s.fz_n},
                       {"f_resultant_n", &fr},
                       {"torque_nm", &s.torque_nm},
                       {"power_w", &s.power_w}});
}

json forces_part(const ReportData& d) {
  const ReportForces& f = *d.forces;
  json out = {{"summary", without_measurements(
                              json::parse(force_summary_json(d.job, f.forces, f.from_s, f.to_s)))},
              {"series", force_series_part(f.forces.series)},
              {"label", f.state_label}};
  if (f.worn) {
    out["worn"] = {
        {"summary",
         without_measurements(json::parse(force_summary_json(d.job, *f.worn, f.from_s, f.to_s)))},
        {"series", force_series_part(f.worn->series)},
        {"label", f.worn_label}};
  }
  return out;
}

// Linear interpolation of (t, v) at x (t ascending); NaN outside.
double interpolate(const std::vector<double>& t, const std::vector<double>& v, double x) {
  if (t.empty() || x < t.front() || x > t.back()) return std::numeric_limits<double>::quiet_NaN();
  const auto it = std::lower_bound(t.begin(), t.end(), x);
  const auto j = static_cast<std::size_t>(it - t.begin());
  if (j == 0) return v[0];
  const double a = (x - t[j - 1]) / (t[j] - t[j - 1]);
  return v[j - 1] + a * (v[j] - v[j - 1]);
}

json calibration_part(const ReportData& d) {
  const ReportCalibration& c = *d.calibration;
  const MeasuredForces& m = c.measured;
  const double shift = c.result.shift_s;
  // The measured record on the model's clock, over the model's window.
  const double t0 = c.model.t_s.empty() ? 0 : c.model.t_s.front();
  const double t1 = c.model.t_s.empty() ? 0 : c.model.t_s.back();
  std::vector<double> mt, mfx, mfy, mfz, mfr;
  for (std::size_t i = 0; i < m.t_s.size(); ++i) {
    const double t = m.t_s[i] - shift;
    if (t < t0 || t > t1) continue;
    mt.push_back(t);
    mfx.push_back(m.fx_n[i]);
    mfy.push_back(m.fy_n[i]);
    mfz.push_back(m.fz_n[i]);
    mfr.push_back(std::hypot(m.fx_n[i], m.fy_n[i], m.fz_n[i]));
  }
  // Residuals at the model's steps: measured (interpolated) less model, per axis.
  const ForceSeries& s = c.model;
  std::vector<double> rx(s.t_s.size()), ry(s.t_s.size()), rz(s.t_s.size());
  for (std::size_t i = 0; i < s.t_s.size(); ++i) {
    rx[i] = interpolate(mt, mfx, s.t_s[i]) - s.fx_n[i];
    ry[i] = interpolate(mt, mfy, s.t_s[i]) - s.fy_n[i];
    rz[i] = interpolate(mt, mfz, s.t_s[i]) - s.fz_n[i];
  }
  json out = {{"summary", json::parse(calibration_json(c.result))},
              {"measured_file", c.measured_file},
              {"model", force_series_part(s)},
              {"residual",
               series_block({{"t_s", &s.t_s}, {"f_x_n", &rx}, {"f_y_n", &ry}, {"f_z_n", &rz}})}};
  if (mt.size() >= 2) {
    out["measured"] = series_block(
        {{"t_s", &mt}, {"f_x_n", &mfx}, {"f_y_n", &mfy}, {"f_z_n", &mfz}, {"f_resultant_n", &mfr}});
  }
  return out;
}

json simulation_part(const ReportData& d, const RunHooks& hooks) {
  const ReportSimulation& rs = *d.simulation;
  const JobSimulation& js = rs.sim;
  const SimResult& r = js.result;
  json out = {
      {"summary", without_measurements(json::parse(simulation_json(
                      d.job, js, rs.from_s, rs.to_s, rs.wall_s, rs.memory_estimate_bytes)))}};
  // Per step: removed volume (all teeth), largest and mean chip, engaged segments.
  const std::size_t n = r.steps.size();
  std::vector<double> t(n), removed(n), hmax(n), hmean(n), segs(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SimStep& st = r.steps[i];
    t[i] = st.t_s;
    removed[i] = std::accumulate(st.removed_mm3.begin(), st.removed_mm3.end(), 0.0);
    hmax[i] = st.h_max_mm;
    hmean[i] = st.h_mean_mm;
    segs[i] = st.engaged_segments;
  }
  if (n >= 2) {
    out["series"] = series_block({{"t_s", &t},
                                  {"removed_mm3", &removed},
                                  {"h_max_mm", &hmax},
                                  {"h_mean_mm", &hmean},
                                  {"engaged_segments", &segs}});
  }
  // The chip map: the largest chip of each (segment, time bin).
  const std::size_t rows = static_cast<std::size_t>(std::max(r.segments_per_tooth, 0)) *
                           static_cast<std::size_t>(std::max(d.job.tool.teeth, 0));
  if (n >= 2 && rows > 0 && !r.chip_map.empty()) {
    const std::size_t cols = std::min(n, kMapColumns);
    std::vector<double> map(rows * cols, std::numeric_limits<double>::quiet_NaN());
    for (const ChipEntry& c : r.chip_map) {
      if (c.segment >= rows) continue;
      const std::size_t col = static_cast<std::size_t>(c.step) * cols / n;
      double& cell = map[c.segment * cols + col];
      if (!(cell >= c.h_mm)) cell = c.h_mm;
    }
    json cm = grid16(map, cols, rows);
    cm["t0_s"] = number(t.front());
    cm["t1_s"] = number(t.back());
    cm["segments_per_tooth"] = r.segments_per_tooth;
    cm["teeth"] = d.job.tool.teeth;
    out["chip_map"] = cm;
  }
  hooks.check("report: interrupted");
  // The machined surface within the triangle budget: a grid of (nx - 1)(ny - 1) quads.
  if (js.work) {
    double step = default_surface_step_mm(*js.work);
    HeightField f = surface_height_field(*js.work, step);
    for (int k = 0; k < 20; ++k) {
      const double tris = 2.0 * static_cast<double>(f.x_mm_of_column.size() - 1) *
                          static_cast<double>(f.y_mm_of_row.size() - 1);
      if (tris <= static_cast<double>(report_triangles)) break;
      step *= std::max(1.1, std::sqrt(tris / static_cast<double>(report_triangles)));
      f = surface_height_field(*js.work, step);
    }
    const std::size_t nx = f.x_mm_of_column.size(), ny = f.y_mm_of_row.size();
    std::vector<double> z(nx * ny);  // row-major for the page
    for (std::size_t c = 0; c < nx; ++c) {
      for (std::size_t row = 0; row < ny; ++row) z[row * nx + c] = f.z_mm[c * ny + row];
    }
    json mesh = grid16(z, nx, ny);
    mesh["x0_mm"] = number(f.x_mm_of_column.front());
    mesh["x1_mm"] = number(f.x_mm_of_column.back());
    mesh["y0_mm"] = number(f.y_mm_of_row.front());
    mesh["y1_mm"] = number(f.y_mm_of_row.back());
    mesh["step_mm"] = number(step);
    mesh["bottom_mm"] = number(f.bottom_mm);
    mesh["triangles"] = 2 * (nx - 1) * (ny - 1);
    out["mesh"] = mesh;
    try {
      const HeightMap floor = simulated_floor(d.job, js);
      json fm = grid16(floor.z_mm, floor.nx, floor.ny);
      fm["x0_mm"] = number(floor.x0_mm);
      fm["y0_mm"] = number(floor.y0_mm);
      fm["dx_mm"] = number(floor.dx_mm);
      fm["dy_mm"] = number(floor.dy_mm);
      // Keep the map within the heat map's budget: every k-th row and column.
      out["floor"] = fm;
    } catch (const InputError& e) {
      out["floor_note"] = e.what();
    }
  }
  return out;
}

json monitor_part(const ReportData& d) {
  const ReportMonitor& mo = *d.monitor;
  const MonitorReport& r = mo.report;
  json out = {{"summary", json::parse(monitor_json(r, mo.signal_file, mo.signal, mo.settings))},
              {"kf", series_block({{"t_s", &r.kf.t_s},
                                   {"k_f", &r.kf.k_f},
                                   {"rms_low", &r.kf.rms_low},
                                   {"rms_high", &r.kf.rms_high}})}};
  const auto idx = all_indices(mo.spectrum.f_hz.size());
  if (!idx.empty()) {
    out["spectrum"] = series_block({{"f_hz", &mo.spectrum.f_hz}, {"psd", &mo.spectrum.psd}});
  }
  const Spectrogram& sg = mo.spectrogram;
  if (!sg.t_s.empty() && !sg.f_hz.empty()) {
    const std::size_t frames = sg.t_s.size(), bins = sg.f_hz.size();
    // A spectrogram is read by eye: 600 x 256 cells (the full one is `spectrum --spectrogram`).
    const std::size_t cols = std::min<std::size_t>(frames, 600);
    const std::size_t rows = std::min<std::size_t>(bins, 256);
    std::vector<double> map(rows * cols, -std::numeric_limits<double>::infinity());
    for (std::size_t c = 0; c < cols; ++c) {
      for (std::size_t f = bin_start(c, frames, cols); f < bin_start(c + 1, frames, cols); ++f) {
        for (std::size_t rr = 0; rr < rows; ++rr) {
          for (std::size_t b = bin_start(rr, bins, rows); b < bin_start(rr + 1, bins, rows); ++b) {
            map[rr * cols + c] = std::max(map[rr * cols + c], sg.db[f][b]);
          }
        }
      }
    }
    json m = grid16(map, cols, rows);
    m["t0_s"] = number(sg.t_s.front());
    m["t1_s"] = number(sg.t_s.back());
    m["f0_hz"] = number(sg.f_hz.front());
    m["f1_hz"] = number(sg.f_hz.back());
    out["spectrogram"] = m;
  }
  return out;
}

}  // namespace

std::vector<std::size_t> decimation_indices(std::size_t samples,
                                            const std::vector<const std::vector<double>*>& ys,
                                            std::size_t columns) {
  if (columns == 0 || samples <= 2 * columns) return all_indices(samples);
  std::vector<std::size_t> out;
  out.reserve(columns * (2 + 2 * ys.size()));
  for (std::size_t c = 0; c < columns; ++c) {
    const std::size_t a = bin_start(c, samples, columns), b = bin_start(c + 1, samples, columns);
    if (a >= b) continue;
    const std::size_t run_first = out.size();
    out.push_back(a);
    out.push_back(b - 1);
    for (const std::vector<double>* y : ys) {
      std::size_t lo = b, hi = b;
      for (std::size_t i = a; i < b; ++i) {
        const double v = (*y)[i];
        if (std::isnan(v)) continue;
        if (lo == b || v < (*y)[lo]) lo = i;
        if (hi == b || v > (*y)[hi]) hi = i;
      }
      if (lo != b) out.push_back(lo), out.push_back(hi);
    }
    std::sort(out.begin() + static_cast<std::ptrdiff_t>(run_first), out.end());
    out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(run_first), out.end()),
              out.end());
  }
  return out;
}

std::string report_data_json(const ReportData& d, const RunHooks& hooks) {
  if (hooks.phase) hooks.phase("writing report");
  const auto step = [&hooks](std::size_t k) {
    hooks.check("report: interrupted");
    if (hooks.progress) hooks.progress(k, 10);
  };
  json doc = {
      {"version", kVersion},        {"job_file", d.job_file},
      {"gcode_file", d.gcode_file}, {"job_text", d.job_text},
      {"overrides", d.overrides},   {"command", d.command},
      {"notes", d.notes},           {"summary", json::parse(metrics_json(d.job, d.metrics))}};
  step(1);
  doc["path"] = path_part(d);
  step(2);
  doc["engagement"] = engagement_part(d);
  step(3);
  doc["walls"] = walls_part(d);
  step(4);
  if (d.mechanism) doc["mechanism"] = mechanism_part(d);
  step(5);
  if (d.forces) doc["forces"] = forces_part(d);
  if (d.calibration) doc["calibration"] = calibration_part(d);
  step(6);
  if (d.simulation) doc["simulation"] = simulation_part(d, hooks);
  step(7);
  if (d.monitor) doc["monitor"] = monitor_part(d);
  step(8);
  if (d.study) {
    doc["study"] = json::parse(study_json(d.study->varies, d.study->points));
  }
  if (d.pareto) {
    const ReportPareto& p = *d.pareto;
    json points = json::array();
    for (std::size_t i = 0; i < p.values.size(); ++i) {
      json g = json::array();
      for (const double v : p.goal_values[i]) g.push_back(number(v));
      points.push_back({{"values", p.values[i]}, {"goals", g}});
    }
    doc["pareto"] = {
        {"keys", p.keys}, {"goals", p.goals}, {"maximize", p.maximize}, {"points", points}};
  }
  if (d.feed) {
    const FeedOptimizeResult& f = *d.feed;
    json part = {{"summary", json::parse(feed_summary_json(f))},
                 {"before", series_block({{"s_mm", &f.s_before_mm},
                                          {"t_s", &f.t_before_s},
                                          {"feed_mm_per_min", &f.feed_before},
                                          {"h_max_mm", &f.h_before}})},
                 {"after", series_block({{"s_mm", &f.s_after_mm},
                                         {"t_s", &f.t_after_s},
                                         {"feed_mm_per_min", &f.feed_after},
                                         {"h_max_mm", &f.h_after}})}};
    if (f.forces && !f.force_s_before_mm.empty() && !f.force_s_after_mm.empty()) {
      part["force_before"] =
          series_block({{"s_mm", &f.force_s_before_mm}, {"f_n", &f.force_before_series_n}});
      part["force_after"] =
          series_block({{"s_mm", &f.force_s_after_mm}, {"f_n", &f.force_after_series_n}});
    }
    doc["feed"] = std::move(part);
  }
  step(9);
  // "</" inside a script element would end it: JSON allows "<\/" for "</".
  std::string text = doc.dump(-1, ' ', false, json::error_handler_t::replace);
  std::string safe;
  safe.reserve(text.size() + 64);
  for (std::size_t i = 0; i < text.size(); ++i) {
    safe += text[i];
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') safe += '\\';
  }
  step(10);
  return safe;
}

std::string report_html(const ReportData& d, const RunHooks& hooks) {
  const std::string data = report_data_json(d, hooks);
  std::string title = "trochomill report";
  if (!d.job_file.empty()) title += ": " + d.job_file;
  std::string escaped;
  for (const char c : title) {
    switch (c) {
      case '<':
        escaped += "&lt;";
        break;
      case '>':
        escaped += "&gt;";
        break;
      case '&':
        escaped += "&amp;";
        break;
      default:
        escaped += c;
    }
  }
  std::string html;
  html.reserve(data.size() + web::report_script().size() + web::view3d_script().size() + 4096);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<meta name=\"generator\" content=\"trochomill " + std::string(kVersion) + "\">\n";
  html += "<title>" + escaped + "</title>\n<style>\n";
  html += web::report_style();
  html += "\n</style>\n</head>\n<body>\n<main id=\"report\"></main>\n";
  html += "<script type=\"application/json\" id=\"trochomill-data\">";
  html += data;
  html += "</script>\n";
  if (d.simulation) {  // three.js only when there is a 3D view
    html += "<script>\n";
    html += web::view3d_script();
    html += "\n</script>\n";
  }
  html += "<script>\n";
  html += web::report_script();
  html += "\n</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace trochomill
