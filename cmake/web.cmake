# The report's browser side (docs/architecture.md, "The report"): npm installs the packages of
# web/package-lock.json (uPlot, three.js, esbuild, playwright-core) from the npm registry into
# the build tree, esbuild bundles web/src into two scripts and a stylesheet, and
# embed_web.cmake turns them into a C++ source of the report module. Nothing of it is
# committed; `npm ci` runs again only when the lock file changes.
find_program(TROCHOMILL_NPM npm)
find_program(TROCHOMILL_NODE node)
if(NOT TROCHOMILL_NPM OR NOT TROCHOMILL_NODE)
  message(FATAL_ERROR "trochomill's report is bundled with Node.js and npm at build time: "
                      "scripts/install-deps installs them (Debian's nodejs and npm)")
endif()
set(TROCHOMILL_WEB_DIR ${PROJECT_BINARY_DIR}/web)
file(MAKE_DIRECTORY ${TROCHOMILL_WEB_DIR})  # the commands below run in it
set(web_src ${PROJECT_SOURCE_DIR}/web)
add_custom_command(
  OUTPUT ${TROCHOMILL_WEB_DIR}/npm.stamp
  COMMAND ${CMAKE_COMMAND} -E make_directory ${TROCHOMILL_WEB_DIR}
  COMMAND ${CMAKE_COMMAND} -E copy ${web_src}/package.json ${web_src}/package-lock.json
          ${TROCHOMILL_WEB_DIR}
  COMMAND ${TROCHOMILL_NPM} ci --no-audit --no-fund --ignore-scripts --loglevel=error
  COMMAND ${CMAKE_COMMAND} -E touch ${TROCHOMILL_WEB_DIR}/npm.stamp
  DEPENDS ${web_src}/package.json ${web_src}/package-lock.json
  WORKING_DIRECTORY ${TROCHOMILL_WEB_DIR}
  COMMENT "npm ci: the report's browser libraries into ${TROCHOMILL_WEB_DIR}/node_modules"
  VERBATIM)
file(GLOB web_sources CONFIGURE_DEPENDS ${web_src}/src/*.js ${web_src}/src/*.css)
set(esbuild ${TROCHOMILL_NODE} ${TROCHOMILL_WEB_DIR}/node_modules/esbuild/bin/esbuild)
set(esbuild_flags --bundle --minify --format=iife --target=es2020 --log-level=warning
                  --legal-comments=inline)
add_custom_command(
  OUTPUT ${TROCHOMILL_WEB_DIR}/dist/report.js ${TROCHOMILL_WEB_DIR}/dist/report.css
         ${TROCHOMILL_WEB_DIR}/dist/view3d.js
  COMMAND ${CMAKE_COMMAND} -E copy_directory ${web_src}/src ${TROCHOMILL_WEB_DIR}/src
  COMMAND ${esbuild} src/report.js ${esbuild_flags} --outfile=dist/report.js
  COMMAND ${esbuild} src/view3d.js ${esbuild_flags} --global-name=TrochomillView3D
          --outfile=dist/view3d.js
  DEPENDS ${TROCHOMILL_WEB_DIR}/npm.stamp ${web_sources}
  WORKING_DIRECTORY ${TROCHOMILL_WEB_DIR}
  COMMENT "esbuild: the report's scripts"
  VERBATIM)
set(TROCHOMILL_WEB_ASSETS ${PROJECT_BINARY_DIR}/generated/web_assets.cpp)
add_custom_command(
  OUTPUT ${TROCHOMILL_WEB_ASSETS}
  COMMAND ${CMAKE_COMMAND} -DDIST=${TROCHOMILL_WEB_DIR}/dist -DOUT=${TROCHOMILL_WEB_ASSETS}
          -P ${PROJECT_SOURCE_DIR}/cmake/embed_web.cmake
  DEPENDS ${TROCHOMILL_WEB_DIR}/dist/report.js ${TROCHOMILL_WEB_DIR}/dist/report.css
          ${TROCHOMILL_WEB_DIR}/dist/view3d.js ${PROJECT_SOURCE_DIR}/cmake/embed_web.cmake
  COMMENT "Embedding the report's scripts"
  VERBATIM)
