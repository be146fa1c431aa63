# mocapctl with file names outside any ANSI code page: a capture, its truth, the calibration, the
# accuracy JSON and a BVH, all in a folder named with umlauts and Japanese. Run by ctest as
#   cmake -DMOCAPCTL=... -DWORKDIR=... [-DEMULATOR=wine] -P mocapctl_unicode_paths.cmake
# On Windows (under Wine) this is what tells UTF-8 arguments and wide file calls from main's
# ANSI argv, which would turn the Japanese characters into '?' and write somewhere else.
foreach(var MOCAPCTL WORKDIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "${var} is not set")
  endif()
endforeach()

set(dir "${WORKDIR}/mocap-äöü-日本")
file(REMOVE_RECURSE "${WORKDIR}")
file(MAKE_DIRECTORY "${dir}")

function(run_mocapctl)
  execute_process(COMMAND ${EMULATOR} "${MOCAPCTL}" ${ARGN}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "mocapctl ${ARGN} exited ${rc}\n${out}\n${err}")
  endif()
endfunction()

run_mocapctl(synth --out "${dir}/walk 歩行.cap" --truth "${dir}/walk 歩行.truth.csv"
             --motion walk --seconds 3 --seed 3)
foreach(made "walk 歩行.cap" "walk 歩行.truth.csv")
  if(NOT EXISTS "${dir}/${made}")
    file(GLOB found "${WORKDIR}/*" "${dir}/*")
    message(FATAL_ERROR "synth did not write ${dir}/${made}; found: ${found}")
  endif()
endforeach()

# Sensor level: the capture against its truth, the calibration saved.
run_mocapctl(replay "${dir}/walk 歩行.cap" --truth "${dir}/walk 歩行.truth.csv"
             --save-calibration "${dir}/較正.calibration" --csv "${dir}/向き.csv")
# Through the model with that calibration: a BVH and the poses as CSV.
run_mocapctl(replay "${dir}/walk 歩行.cap" --calibration "${dir}/較正.calibration"
             --out "${dir}/姿勢.bvh" --pose-csv "${dir}/姿勢.csv")
foreach(made "較正.calibration" "向き.csv" "姿勢.bvh" "姿勢.csv")
  if(NOT EXISTS "${dir}/${made}")
    file(GLOB found "${WORKDIR}/*" "${dir}/*")
    message(FATAL_ERROR "replay did not write ${dir}/${made}; found: ${found}")
  endif()
endforeach()

file(STRINGS "${dir}/姿勢.bvh" frames_line REGEX "^Frames:")
string(REGEX REPLACE "^Frames:[ \t]*([0-9]+).*" "\\1" frames "${frames_line}")
if(NOT frames MATCHES "^[0-9]+$" OR frames LESS 100)
  message(FATAL_ERROR "the BVH written under the Unicode name has '${frames_line}'")
endif()
file(STRINGS "${dir}/姿勢.csv" pose_rows)
list(LENGTH pose_rows rows)
if(rows LESS 100)
  message(FATAL_ERROR "the pose CSV written under the Unicode name has ${rows} lines")
endif()
message(STATUS "mocapctl read and wrote every file under ${dir}: ${frames} BVH frames")
