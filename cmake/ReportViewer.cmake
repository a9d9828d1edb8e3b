# The report viewer (report/: our JavaScript + three.js, bundled by esbuild)
# is embedded in the curvflow tool as a generated C file, so that
# `curvflow report` writes one self-contained HTML file. Building it needs
# node and npm (`npm ci` from report/package-lock.json into the build tree).
# Without them the tool still builds, with a stub that makes `report` fail
# with a message saying why (docs/report.md).
#
# CURVFLOW_REPORT: AUTO (default) builds the viewer when node and npm are
# found and falls back to the stub if npm ci or the bundle fails; ON makes
# either a configure or build error; OFF always uses the stub.
set(CURVFLOW_REPORT AUTO CACHE STRING "Embed the HTML report viewer: AUTO, ON or OFF (needs node + npm)")
set_property(CACHE CURVFLOW_REPORT PROPERTY STRINGS AUTO ON OFF)

set(CURVFLOW_REPORT_DIR ${CMAKE_BINARY_DIR}/report)
set(CURVFLOW_REPORT_C ${CURVFLOW_REPORT_DIR}/report_bundle.c)
file(MAKE_DIRECTORY ${CURVFLOW_REPORT_DIR})

find_program(CURVFLOW_NODE NAMES node nodejs)
find_program(CURVFLOW_NPM npm)

set(_cf_report_required OFF)
if(CURVFLOW_REPORT STREQUAL "ON")
  set(_cf_report_required ON)
endif()

if(NOT CURVFLOW_REPORT STREQUAL "OFF" AND CURVFLOW_NODE AND CURVFLOW_NPM)
  file(GLOB _cf_report_sources CONFIGURE_DEPENDS ${CMAKE_SOURCE_DIR}/report/src/*)
  add_custom_command(
    OUTPUT ${CURVFLOW_REPORT_C}
    COMMAND ${CMAKE_COMMAND} -DNODE=${CURVFLOW_NODE} -DNPM=${CURVFLOW_NPM}
            -DSOURCE_DIR=${CMAKE_SOURCE_DIR}/report -DWORK_DIR=${CURVFLOW_REPORT_DIR}
            -DOUT_C=${CURVFLOW_REPORT_C} -DREQUIRED=${_cf_report_required}
            -P ${CMAKE_SOURCE_DIR}/cmake/report_bundle.cmake
    DEPENDS ${CMAKE_SOURCE_DIR}/report/package.json ${CMAKE_SOURCE_DIR}/report/package-lock.json
            ${CMAKE_SOURCE_DIR}/report/build.mjs ${_cf_report_sources} ${CMAKE_SOURCE_DIR}/cmake/report_bundle.cmake
    COMMENT "Bundling the report viewer (npm ci + esbuild)"
    VERBATIM)
  message(STATUS "curvflow report viewer: bundled at build time with ${CURVFLOW_NPM} and ${CURVFLOW_NODE}")
else()
  if(CURVFLOW_REPORT STREQUAL "OFF")
    set(_cf_reason "this curvflow was configured with -DCURVFLOW_REPORT=OFF")
  else()
    set(_cf_reason "node and npm were not found when this curvflow was configured; install them (Debian: nodejs npm) and re-run cmake")
    if(_cf_report_required)
      message(FATAL_ERROR "CURVFLOW_REPORT=ON but ${_cf_reason}")
    endif()
    message(WARNING "curvflow report viewer not built: ${_cf_reason}; `curvflow report` will say so")
  endif()
  include(${CMAKE_SOURCE_DIR}/cmake/report_stub.cmake)
  curvflow_report_stub(${CURVFLOW_REPORT_C} "${_cf_reason}")
endif()
target_sources(curvflow PRIVATE ${CURVFLOW_REPORT_C})
