# Lays out the systemd units and the folder of the nodes' DCDs at install time (cmake --install,
# cpack), with the prefix the install is given: `cmake --install build --prefix P` stays inside P
# and its units name P's programs, whatever prefix the build was configured with. Under systemd's
# own prefix (/usr: the Debian packages) the units go to systemd's unit folder and the DCDs to
# /etc, as a distribution lays them out; a packager's RSCA_SYSTEMD_UNIT_DIR wins. DESTDIR is
# honoured by file(INSTALL). Called from tools/systemd/CMakeLists.txt with:
#   RSCA_UNITS_SOURCE_DIR, RSCA_UNITS_WORK_DIR, RSCA_UNITS_BINDIR, RSCA_UNITS_DATADIR,
#   RSCA_UNITS_SYSCONFDIR (GNUInstallDirs' relative folders), RSCA_UNITS_DIR (a packager's
#   choice, may be empty), RSCA_UNITS_SYSTEMD_PREFIX and RSCA_UNITS_SYSTEMD_DIR (pkg-config
#   systemd's prefix and systemdsystemunitdir, may be empty).

# `dir` under the install's prefix, unless it is absolute.
function(rsca_under_prefix dir out)
  if(IS_ABSOLUTE "${dir}")
    set(${out} "${dir}" PARENT_SCOPE)
  else()
    set(${out} "${CMAKE_INSTALL_PREFIX}/${dir}" PARENT_SCOPE)
  endif()
endfunction()

set(rsca_system_prefix FALSE)
if(RSCA_UNITS_SYSTEMD_PREFIX AND CMAKE_INSTALL_PREFIX STREQUAL RSCA_UNITS_SYSTEMD_PREFIX)
  set(rsca_system_prefix TRUE)
endif()

if(RSCA_UNITS_DIR)
  rsca_under_prefix("${RSCA_UNITS_DIR}" unit_dir)
elseif(rsca_system_prefix AND RSCA_UNITS_SYSTEMD_DIR)
  set(unit_dir "${RSCA_UNITS_SYSTEMD_DIR}")
else()
  set(unit_dir "${CMAKE_INSTALL_PREFIX}/lib/systemd/system")
endif()
if(rsca_system_prefix)
  set(RSCA_UNIT_SYSCONFDIR "/etc")
else()
  rsca_under_prefix("${RSCA_UNITS_SYSCONFDIR}" RSCA_UNIT_SYSCONFDIR)
endif()
rsca_under_prefix("${RSCA_UNITS_BINDIR}" RSCA_UNIT_BINDIR)
rsca_under_prefix("${RSCA_UNITS_DATADIR}/rsca/profiles" RSCA_UNIT_PROFILESDIR)

set(units "")
foreach(unit rsca-domaind.service rsca-noded@.service)
  configure_file("${RSCA_UNITS_SOURCE_DIR}/${unit}.in" "${RSCA_UNITS_WORK_DIR}/${unit}" @ONLY)
  list(APPEND units "${RSCA_UNITS_WORK_DIR}/${unit}")
endforeach()
file(INSTALL DESTINATION "${unit_dir}" TYPE FILE FILES ${units})
# Where rsca-noded@NAME.service reads its node's DCD (SYSCONFDIR/rsca/nodes/NAME.dcd.xml), empty.
file(INSTALL DESTINATION "${RSCA_UNIT_SYSCONFDIR}/rsca" TYPE DIRECTORY FILES
     "${RSCA_UNITS_WORK_DIR}/nodes")
