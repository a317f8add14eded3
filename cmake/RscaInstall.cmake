# What `cmake --install` puts where (GNUInstallDirs), in two install components that CPack makes
# into two Debian packages (cmake/RscaPackage.cmake):
#   runtime  the daemons, the CLI, the component host, the runtime library, the XML reader module,
#            the device libraries, the example components, the schemas and the default profiles (package rsca);
#   dev      the component and device SDK: headers, the CMake package (find_package(rsca)) with
#            rsca_add_component and rsca_add_device, and a pkg-config file (package rsca-dev).
# The programs find the rest from their own folder (common/install_layout.hpp), so an installed
# tree works under any prefix and from a DESTDIR.
include(CMakePackageConfigHelpers)

set(RSCA_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/rsca)

install(TARGETS rsca rsca-domaind rsca-noded rsca-component-host rsca-sim-run
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
# The XML reader module and the device libraries, where common/install_layout.hpp finds them.
get_property(rsca_devices GLOBAL PROPERTY RSCA_DEVICE_TARGETS)
install(TARGETS rsca_xml_reader ${rsca_devices} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/rsca
        COMPONENT runtime)
install(DIRECTORY schemas/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rsca/schemas COMPONENT runtime
        FILES_MATCHING PATTERN "*.xsd")
install(DIRECTORY profiles/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rsca/profiles COMPONENT runtime
        FILES_MATCHING PATTERN "*.xml")
# The folder of the nodes' DCDs is laid out with the units, at install time
# (tools/systemd/install_units.cmake).

# The SDK.
install(TARGETS rsca_runtime rsca_sdk_headers rsca_component_headers rsca_device_headers EXPORT rscaTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT dev)
foreach(header ${RSCA_SDK_HEADERS})
  get_filename_component(folder ${header} DIRECTORY)
  install(FILES core_framework/${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rsca/${folder}
          COMPONENT dev)
endforeach()
install(EXPORT rscaTargets NAMESPACE rsca:: DESTINATION ${RSCA_INSTALL_CMAKEDIR} COMPONENT dev)
configure_package_config_file(cmake/rscaConfig.cmake.in
                              ${CMAKE_BINARY_DIR}/cmake/rscaConfig.cmake
                              INSTALL_DESTINATION ${RSCA_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_BINARY_DIR}/cmake/rscaConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_BINARY_DIR}/cmake/rscaConfig.cmake
              ${CMAKE_BINARY_DIR}/cmake/rscaConfigVersion.cmake cmake/RscaAddComponent.cmake
              cmake/RscaAddDevice.cmake DESTINATION ${RSCA_INSTALL_CMAKEDIR} COMPONENT dev)

# pkg-config: the prefix from the file's own place, so that a DESTDIR tree answers for itself.
file(RELATIVE_PATH RSCA_PC_TO_PREFIX /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
configure_file(cmake/rsca.pc.in ${CMAKE_BINARY_DIR}/cmake/rsca.pc @ONLY)
install(FILES ${CMAKE_BINARY_DIR}/cmake/rsca.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig
        COMPONENT dev)
