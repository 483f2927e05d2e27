# The LAMMPS version of a source tree (src/version.h) as a number YYYYMMDD,
# and the check that it is one PE-JUMP builds against: LAMMPS 4 Feb 2025 or
# newer (tested: 4 Feb 2025 and 4 Jul 2026). Older trees lack interfaces the
# styles use (utils::missing_cmd_args, Modify::get_fix_list,
# Neighbor::get_xhold, Info::get_variable_info, ...) and would fail to
# compile with a long list of errors.
set(PEJUMP_OLDEST_LAMMPS 20250204)
set(PEJUMP_OLDEST_LAMMPS_NAME "4 Feb 2025")

function(pejump_lammps_version top out_number out_name)
  set(_file "${top}/src/version.h")
  if(NOT EXISTS "${_file}")
    message(FATAL_ERROR "${top} has no src/version.h: not a LAMMPS source tree")
  endif()
  file(STRINGS "${_file}" _line REGEX "^#define LAMMPS_VERSION ")
  if(NOT _line MATCHES "\"([0-9]+) ([A-Za-z]+) ([0-9]+)\"")
    message(FATAL_ERROR "Could not read the LAMMPS version from ${_file}: ${_line}")
  endif()
  set(_day ${CMAKE_MATCH_1})
  set(_month ${CMAKE_MATCH_2})
  set(_year ${CMAKE_MATCH_3})
  set(_months Jan Feb Mar Apr May Jun Jul Aug Sep Oct Nov Dec)
  list(FIND _months "${_month}" _index)
  if(_index LESS 0)
    message(FATAL_ERROR "Could not read the LAMMPS version from ${_file}: month ${_month}")
  endif()
  math(EXPR _number "${_year} * 10000 + (${_index} + 1) * 100 + ${_day}")
  set(${out_number} ${_number} PARENT_SCOPE)
  set(${out_name} "${_day} ${_month} ${_year}" PARENT_SCOPE)
endfunction()

function(pejump_check_lammps_version top)
  pejump_lammps_version("${top}" _number _name)
  message(STATUS "LAMMPS version of the source tree: ${_name}")
  if(_number LESS PEJUMP_OLDEST_LAMMPS AND NOT PEJUMP_SKIP_VERSION_CHECK)
    message(FATAL_ERROR
      "PE-JUMP needs LAMMPS ${PEJUMP_OLDEST_LAMMPS_NAME} or newer (tested with 4 Feb 2025 and "
      "4 Jul 2026); ${top} is LAMMPS ${_name}, which lacks interfaces the styles use "
      "(utils::missing_cmd_args, Modify::get_fix_list, Neighbor::get_xhold, ...). Point "
      "LAMMPS_SOURCE_DIR at a newer tree, or leave it out to fetch LAMMPS 4 Feb 2025. "
      "(-D PEJUMP_SKIP_VERSION_CHECK=ON tries anyway.)")
  endif()
endfunction()
