# Run at every build (cmake -P), not at configure time: writes OUT, the header that names the source
# revision the binaries were built from, so a record file never names a revision older than its code.
# "-dirty" marks tracked files that differ from HEAD. file(CONFIGURE) rewrites OUT only when its text
# changes, so an unchanged revision recompiles nothing.
execute_process(COMMAND git rev-parse --short=12 HEAD
  WORKING_DIRECTORY ${SOURCE_DIR} OUTPUT_VARIABLE revision RESULT_VARIABLE failed
  OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(failed OR NOT revision)
  set(revision unknown)  # a source tree outside git (an exported tarball)
else()
  execute_process(COMMAND git diff --quiet HEAD -- WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE changed)
  if(changed)
    string(APPEND revision "-dirty")
  endif()
endif()
file(CONFIGURE OUTPUT ${OUT} @ONLY CONTENT [[#pragma once
// Generated at build time by coordinator/cmake/git_revision.cmake.
namespace sphfsi::coordinator {
inline constexpr const char* kGitRevision = "@revision@";
}  // namespace sphfsi::coordinator
]])
