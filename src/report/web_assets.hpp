// The report's browser side, embedded at build time (cmake/web.cmake): the bundled scripts
// and stylesheet made by esbuild from web/src with uPlot and three.js from the npm registry.
#pragma once

#include <string_view>

namespace trochomill::web {

/// The page's script: uPlot and the figures (an IIFE; reads the JSON data block).
[[nodiscard]] std::string_view report_script();
/// The page's stylesheet (uPlot's and the report's).
[[nodiscard]] std::string_view report_style();
/// The 3D view: three.js and its orbit controls (an IIFE defining `TrochomillView3D`).
[[nodiscard]] std::string_view view3d_script();

}  // namespace trochomill::web
