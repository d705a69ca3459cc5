// `texture`'s report of profiles and areal surfaces. Part of the report module
// (trochomill/report.hpp includes every part).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/texture.hpp"

namespace trochomill {

/// One evaluated surface of `trochomill texture`.
struct TextureEntry {
  std::string surface;                ///< "left", "right", "floor", "profile" or "surface"
  std::string description;            ///< where the profile or map came from
  ProfileTexture texture;             ///< a profile's texture (when `areal` is empty)
  std::optional<ArealTexture> areal;  ///< an areal surface's texture instead
  /// The areal surface against a predicted one (`texture --against`), and where that came from.
  std::optional<SurfaceComparison> comparison;
  std::string against;
};
/// `texture`'s report: per profile the cut-off (and how it was chosen), Ra, Rq, Rsk, Rku, Rp,
/// Rv, Rz, Rt, RSm, Wa, Wt (mm), evaluation length (mm) and sections; per areal surface the
/// S- and L-filters' nesting indices, the F-operator, and Sa, Sq, Ssk, Sku, Sp, Sv, Sz (mm),
/// Sdr (%), Sal (mm), Str of the S-L surface and the same but Sal and Str of the S-F surface.
[[nodiscard]] std::string texture_json(const std::string& source,
                                       const std::vector<TextureEntry>& entries);
[[nodiscard]] std::string texture_text(const std::string& source,
                                       const std::vector<TextureEntry>& entries);

}  // namespace trochomill
