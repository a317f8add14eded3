# Debian packages (cpack -G DEB, or tools/package): rsca (install component runtime) and rsca-dev
# (component dev). The runtime package's dependencies are computed by dpkg-shlibdeps from what
# its programs link, so they are the Debian packages rsca was built against; the dev package
# depends on the -dev packages its headers include. The packages install under the build's
# prefix (/usr unless given), which the systemd units name.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rsca)
set(CPACK_PACKAGE_VENDOR "rsca")
set(CPACK_PACKAGE_CONTACT "rsca developers <rsca-dev@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGING_INSTALL_PREFIX ${CMAKE_INSTALL_PREFIX})
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_STRIP_FILES ON) # the build's debug info stays in the build (RelWithDebInfo: 190 MB)

set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME rsca)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SHLIBDEPS ON)
# Beside what its programs link: the domain runs binutils' objcopy to deliver code without its
# debug information (domain/delivered_code.hpp).
set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "binutils")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_RECOMMENDS "graphviz") # rsca show --graph svg
# postinst creates the user rsca, whom the nodes run component processes as.
if(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS)
  string(APPEND CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS ", adduser")
else()
  set(CPACK_DEBIAN_RUNTIME_PACKAGE_DEPENDS "adduser")
endif()
set(CPACK_COMPONENT_RUNTIME_DESCRIPTION
    "rsca's domain and node daemons, its CLI, the component host and runtime, the schemas and the default profiles")

set(CPACK_DEBIAN_DEV_PACKAGE_NAME rsca-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
    "rsca (= ${PROJECT_VERSION}), libexpected-dev, libfmt-dev, libspdlog-dev, nlohmann-json3-dev, cyclonedds-dev")
set(CPACK_COMPONENT_DEV_DESCRIPTION
    "rsca's component SDK: headers, find_package(rsca) with rsca_add_component, pkg-config")

# The maintainer scripts (cmake/debian/): the user rsca is made, systemd reloads its units when
# the package installs, upgrades or goes, and the daemons stop before their programs are
# removed; no unit is enabled
# (README, "Install"). Each package has its copyright file where Debian looks for it.
set(rsca_debian ${CMAKE_CURRENT_LIST_DIR}/debian)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_EXTRA
    "${rsca_debian}/postinst;${rsca_debian}/prerm;${rsca_debian}/postrm")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_STRICT_PERMISSION ON) # scripts 0755, as dpkg wants
install(FILES ${rsca_debian}/copyright DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/rsca
        COMPONENT runtime)
install(FILES ${rsca_debian}/copyright DESTINATION ${CMAKE_INSTALL_DATAROOTDIR}/doc/rsca-dev
        COMPONENT dev)

include(CPack)
