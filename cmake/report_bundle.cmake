# Build step of the report viewer (run with cmake -P from ReportViewer.cmake):
# npm ci into WORK_DIR when report/package-lock.json changed, then
# report/build.mjs writes OUT_C. With REQUIRED=OFF a failure (for example no
# access to the npm registry) writes the stub instead, so the tool still
# builds and `curvflow report` names the reason.
include(${CMAKE_CURRENT_LIST_DIR}/report_stub.cmake)

function(fail what output)
  string(STRIP "${output}" output)
  string(REGEX REPLACE "\n.*" "" first_line "${output}")
  if(REQUIRED)
    message(FATAL_ERROR "curvflow report viewer: ${what} failed:\n${output}")
  endif()
  message(WARNING "curvflow report viewer: ${what} failed (${first_line}); `curvflow report` will say so. "
                  "Delete ${WORK_DIR}/report_bundle.c and rebuild to try again.")
  curvflow_report_stub(${OUT_C} "${what} failed when this curvflow was built (${first_line}); see docs/report.md")
endfunction()

foreach(f package.json package-lock.json)
  configure_file(${SOURCE_DIR}/${f} ${WORK_DIR}/${f} COPYONLY)
endforeach()
# npm ci leaves its own copy of the lock in node_modules: reinstall only when
# the committed lock differs from it
set(installed ${WORK_DIR}/node_modules/.curvflow-package-lock.json)
set(need_ci TRUE)
if(EXISTS ${installed})
  file(SHA256 ${installed} a)
  file(SHA256 ${SOURCE_DIR}/package-lock.json b)
  if(a STREQUAL b)
    set(need_ci FALSE)
  endif()
endif()
if(need_ci)
  execute_process(COMMAND ${NPM} ci --no-audit --no-fund --loglevel=error
                  WORKING_DIRECTORY ${WORK_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    fail("npm ci" "${out}")
    return()
  endif()
  configure_file(${SOURCE_DIR}/package-lock.json ${installed} COPYONLY)
endif()
execute_process(COMMAND ${NODE} ${SOURCE_DIR}/build.mjs ${WORK_DIR}/node_modules ${WORK_DIR}/viewer.js ${OUT_C}
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
if(NOT rc EQUAL 0)
  fail("bundling the viewer (node build.mjs)" "${out}")
  return()
endif()
message(STATUS "${out}")
