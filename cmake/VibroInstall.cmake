# `cmake --install build --prefix P`: the shared library, the public headers, the command line,
# the plot tool and the shipped scenes (P/share/vibro/), and a CMake package so that
# `find_package(vibro)` gives the target vibro::vibro.
include(CMakePackageConfigHelpers)

install(TARGETS vibro EXPORT vibroTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/vibro DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS vibro_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(PROGRAMS scripts/vibro_plot.py DESTINATION ${CMAKE_INSTALL_DATADIR}/vibro)
# The independent checker of `vibro prove` certificates (docs/prove.md), on the PATH beside vibro.
install(PROGRAMS scripts/vibro_check_proof.py DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY data/scenes DESTINATION ${CMAKE_INSTALL_DATADIR}/vibro FILES_MATCHING PATTERN "*.toml")

set(VIBRO_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/vibro)
install(EXPORT vibroTargets NAMESPACE vibro:: DESTINATION ${VIBRO_CMAKE_DIR})
configure_package_config_file(cmake/vibroConfig.cmake.in ${PROJECT_BINARY_DIR}/vibroConfig.cmake
                              INSTALL_DESTINATION ${VIBRO_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vibroConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vibroConfig.cmake ${PROJECT_BINARY_DIR}/vibroConfigVersion.cmake
        DESTINATION ${VIBRO_CMAKE_DIR})
