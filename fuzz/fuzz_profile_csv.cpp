// The profile readers and the texture of what they read: a CSV profile (x, z) or a
// simulation's walls.csv; every input gives finite parameters or an InputError. The first
// byte chooses: 0 a profile in mm, 1 a profile in um, 2 the left wall, 3 the right wall, and
// its high bit a given cut-off (0.25 mm) instead of the ISO 21920-3 default; for a wall, bit 6
// its machined part only (the front arc left out, as texture reads a simulate folder).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <optional>
#include <string_view>

#include "trochomill/error.hpp"
#include "trochomill/texture.hpp"

namespace {

void check(const trochomill::ProfileTexture& t) {
  const auto& r = t.roughness;
  for (double v : {t.cutoff_mm, r.ra_mm, r.rq_mm, r.rz_mm, r.rt_mm, r.rsm_mm, t.wa_mm, t.wt_mm}) {
    if (!std::isfinite(v) || v < 0) std::abort();  // heights and lengths: finite, not negative
  }
  if (r.ra_mm > r.rq_mm * (1 + 1e-12) || r.rz_mm > r.rt_mm * (1 + 1e-12)) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  if (size == 0) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);
  const int mode = data[0] & 3;
  const std::optional<double> cutoff =
      (data[0] & 0x80) != 0 ? std::optional<double>(0.25) : std::nullopt;
  try {
    const MeasuredProfile p =
        mode < 2 ? read_profile_csv(text, "fuzz", "", "", mode ? 1e-3 : 1.0)
                 : read_wall_profile_csv(text, "fuzz", mode == 2, {}, (data[0] & 0x40) != 0);
    if (p.z_mm.size() < 2 || !(p.dx_mm > 0)) std::abort();  // the readers promise a profile
    for (double z : p.z_mm) {
      if (!std::isfinite(z)) std::abort();
    }
    check(profile_texture(p.z_mm, p.dx_mm, cutoff));  // as `trochomill texture` does
  } catch (const InputError&) {
  }
  return 0;
}
