// mechanism and recommend: Pivkin 2025's cutting mechanism over a trochoid cycle, and the
// smallest step (or feed per tooth) that keeps a share of the cut in CZIII.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/report/mechanism.hpp"

namespace trochomill::python {

void bind_mechanism(py::module_& m) {
  m.def(
      "mechanism",
      [](const PyJob& pj, const std::optional<std::string>& model,
         std::optional<double> flank_wear_mm) {
        std::vector<Override> more;
        if (model) more.push_back({"mechanism.model", "\"" + *model + "\"", "model"});
        if (flank_wear_mm)
          more.push_back({"tool.flank_wear", fmt::format("{}", *flank_wear_mm), "flank_wear_mm"});
        const Job job = more.empty() ? pj.job : pj.with(more);
        const MechanismSettings& st = job.mechanism;
        const bool use_wear = job.tool.flank_wear_mm > 0;
        MechanismCurve c = mechanism_curve(job, st, use_wear);
        const ZoneSummary z = summarize_zones(c, st, use_wear);
        py::dict out = from_json(mechanism_json(job, st, c, z, use_wear));
        out["theta_deg"] = to_array(degrees(c.theta_rad));
        out["psi_deg"] = to_array(degrees(c.psi_rad));
        out["gamma_k_deg"] = to_array(degrees(c.gamma_k_rad));
        out["kappa_deg"] = to_array(degrees(c.kappa_rad));
        out["k_re_pct"] = to_array(use_wear ? std::move(c.k_re_wear_pct) : std::move(c.k_re_pct));
        if (use_wear) out["k_re_wear_pct"] = out["k_re_pct"];
        out["t_s"] = to_array(std::move(c.t_s));
        out["h_mm"] = to_array(std::move(c.h_mm));
        out["teeth_in_contact"] = to_array(std::move(c.teeth_in_contact));
        out["zone"] = to_array(std::move(c.zone));
        return out;
      },
      py::arg("job"), py::kw_only(), py::arg("model") = py::none(),
      py::arg("flank_wear_mm") = py::none(),
      R"(Chip thickness, K_re and the cutting-mechanism zones over one trochoid cycle (Pivkin
2025): the keys of `trochomill mechanism --json` with the curves as arrays over the cycle:
theta_deg, t_s, h_mm, psi_deg, teeth_in_contact, gamma_k_deg, kappa_deg, k_re_pct (with the
flank wear when the tool has one) and zone (int32: 0 not cutting, 1 CZI, 2 CZII, 3 CZIII).
model: "exact" or "pivkin2025" (default the job's mechanism.model); flank_wear_mm: VB_B (mm).)");

  m.def(
      "recommend",
      [](const PyJob& pj, std::optional<double> share, std::optional<std::string> share_of,
         std::optional<std::string> criterion, std::optional<double> plunger_share, bool feed) {
        std::vector<Override> more;
        if (share) more.push_back({"mechanism.share", fmt::format("{}", *share), "share"});
        if (share_of) more.push_back({"mechanism.share_of", *share_of, "share_of"});
        if (criterion) more.push_back({"mechanism.criterion", *criterion, "criterion"});
        if (plunger_share) {
          more.push_back(
              {"mechanism.plunger_share", fmt::format("{}", *plunger_share), "plunger_share"});
        }
        const Job job = more.empty() ? pj.job : pj.with(more);
        const Recommendation r = recommend(job, job.mechanism, job.tool.flank_wear_mm > 0, feed);
        return from_json(recommendation_json(job, job.mechanism, r, feed));
      },
      py::arg("job"), py::kw_only(), py::arg("share") = py::none(),
      py::arg("share_of") = py::none(), py::arg("criterion") = py::none(),
      py::arg("plunger_share") = py::none(), py::arg("feed") = false,
      R"(The smallest trochoid step (mm), or with feed=True the feed per tooth (mm) at the job's
step, whose cutting part (share_of="cutting", default mechanism.share_of) or whole cycle
(share_of="cycle") is at least `share` (0..1, default mechanism.share) in CZIII; with
criterion="plunger", whose cut keeps CZI to at most `plunger_share` (0..1, default 0.2) of its
first half (Pivkin 2025's plunger criterion): the keys of `trochomill recommend --json` (with
its "explanation").)");
}

}  // namespace trochomill::python
