// texture_profile and texture_areal: roughness and waviness of a profile, and the areal
// texture of a height map, as `trochomill texture` reports them.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "trochomill/report/texture.hpp"
#include "trochomill/texture.hpp"

namespace trochomill::python {

namespace {

// The one surface of a texture JSON document.
py::dict first_surface(const std::string& json) {
  const py::list surfaces = from_json(json)["surfaces"];
  return surfaces[0];
}

}  // namespace

void bind_texture(py::module_& m) {
  m.def(
      "texture_profile",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& z, double dx_mm,
         std::optional<double> lambda_c_mm, std::optional<double> lambda_s_mm, bool robust) {
        TextureEntry e;
        e.surface = "profile";
        const std::vector<double> heights = finite_vector(z, "z_mm");
        e.description = fmt::format("profile of {} points every {:g} mm", heights.size(), dx_mm);
        ProfileFilterOptions o;
        o.lambda_s_mm = lambda_s_mm;
        o.robust = robust;
        e.texture = run_released(
            [&](const RunHooks&) { return profile_texture(heights, dx_mm, lambda_c_mm, o); });
        py::dict out = first_surface(texture_json("<array>", {e}));
        out["profile"] = profile_arrays(e.texture);
        return out;
      },
      py::arg("z_mm"), py::arg("dx_mm"), py::kw_only(), py::arg("lambda_c_mm") = py::none(),
      py::arg("lambda_s_mm") = py::none(), py::arg("robust") = false,
      R"(Roughness and waviness of a profile (ISO 16610-21 Gaussian filter, ISO 21920-2
parameters), as `trochomill texture` reports a CSV profile: z_mm heights (mm) every dx_mm (mm);
lambda_c_mm the cut-off (default the ISO 21920-3 one for its Ra, found by iteration and
stated), lambda_s_mm the S-filter, robust the ISO 16610-31 robust filter. Returns the keys
of the CLI's JSON surface (ra_mm, rq_mm, rz_mm, rt_mm, rsm_mm, wa_mm, wt_mm, lambda_c_mm,
evaluation_length_mm, ...) and "profile": x_mm (along the input), roughness_mm (R profile)
and waviness_mm (W profile, the filter's mean line) over the evaluation length.)");

  m.def(
      "texture_areal",
      [](const py::array_t<double, py::array::c_style | py::array::forcecast>& z, double dx_mm,
         double dy_mm, std::optional<double> s_mm, std::optional<double> l_mm,
         const std::string& form, int degree, std::optional<double> memory_limit_gb) {
        if (z.ndim() != 2) {
          throw InputError(fmt::format(
              "z_mm: a 2-D array (rows along y, columns along x), got {} dimensions", z.ndim()));
        }
        // An areal texture holds about 12 copies of the map at its peak (as the CLI counts).
        check_memory("texture_areal", static_cast<double>(z.size()) * 100.0 + 40e6, memory_limit_gb,
                     "evaluate a smaller map");
        HeightMap map;
        map.ny = static_cast<std::size_t>(z.shape(0));
        map.nx = static_cast<std::size_t>(z.shape(1));
        map.dx_mm = dx_mm;
        map.dy_mm = dy_mm;
        map.z_mm.assign(z.data(), z.data() + z.size());
        map.description =
            fmt::format("map of {} x {} points every {:g} x {:g} mm", map.nx, map.ny, dx_mm, dy_mm);
        check_height_map(map, "z_mm");
        ArealFilterOptions o;
        o.s_mm = s_mm;
        o.l_mm = l_mm;
        o.degree = degree;
        if (form == "plane") {
          o.form = FormRemoval::plane;
        } else if (form == "polynomial") {
          o.form = FormRemoval::polynomial;
        } else if (form == "none") {
          o.form = FormRemoval::none;
        } else {
          throw InputError(fmt::format("form '{}': plane, polynomial or none", form));
        }
        TextureEntry e;
        e.surface = "surface";
        e.description = map.description;
        e.areal = run_released([&](const RunHooks&) { return areal_texture(map, o); });
        return first_surface(texture_json("<array>", {e}));
      },
      py::arg("z_mm"), py::arg("dx_mm"), py::arg("dy_mm"), py::kw_only(),
      py::arg("s_mm") = py::none(), py::arg("l_mm") = py::none(), py::arg("form") = "plane",
      py::arg("degree") = 2, py::arg("memory_limit_gb") = py::none(),
      R"(Areal texture of a height map (ISO 16610-61 Gaussian filter, ISO 25178-2 parameters), as
`trochomill texture` reports an X3P surface: z_mm heights (mm) as (rows along y, columns
along x), every dx_mm along x and dy_mm along y; s_mm the S-filter's nesting index (default
none), l_mm the L-filter's (default the ISO 21920-3 cut-off for the S-L surface's Sa), form
the F-operator ("plane", "polynomial" of `degree`, "none"). Returns the keys of the CLI's
JSON surface: the S-F and S-L surfaces' Sa, Sq, Ssk, Sku, Sp, Sv, Sz (mm), Sdr (%), Sal (mm)
and Str, with the filters used. A simulation's floor (simulate(...)["floor"]) is such a map.)");
}

}  // namespace trochomill::python
