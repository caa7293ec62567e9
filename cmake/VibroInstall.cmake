# `cmake --install build --prefix P`: the shared library, the public headers, the command line,
# the plot tool, the CSV tools (P/bin/vibro-branch-to-csv, vibro-events-to-csv, vibro-auto-to-csv), the shipped
# scenes and the reference problems (P/share/vibro/scenes, P/share/vibro/benchmarks), and a CMake
# package so that `find_package(vibro)` gives the target vibro::vibro.
include(CMakePackageConfigHelpers)

install(TARGETS vibro EXPORT vibroTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/vibro DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS vibro_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS vibro_prove LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})  # beside libvibro (prove_loader.cpp)
install(TARGETS vibro_cvode LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})  # beside libvibro (cvode_loader.cpp)
install(TARGETS vibro_parallel LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})  # beside libvibro (parallel_for.cpp)
if(VIBRO_MPI)  # beside libvibro, where src/studies/distribute.cpp looks for it
  install(TARGETS vibro_mpi LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
endif()
install(PROGRAMS scripts/vibro_plot.py DESTINATION ${CMAKE_INSTALL_DATADIR}/vibro)
# The independent checker of `vibro prove` certificates (docs/prove.md), on the PATH beside vibro.
install(PROGRAMS scripts/vibro_check_proof.py DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY data/scenes DESTINATION ${CMAKE_INSTALL_DATADIR}/vibro FILES_MATCHING PATTERN "*.toml")
# What docs/validation.md has users run: the CSV converters for `vibro validate` and `vibro score`
# (scripts/*_to_csv.py in a checkout), and the reference problems `vibro score` compares with.
install(PROGRAMS scripts/branch_to_csv.py DESTINATION ${CMAKE_INSTALL_BINDIR} RENAME vibro-branch-to-csv)
install(PROGRAMS scripts/events_to_csv.py DESTINATION ${CMAKE_INSTALL_BINDIR} RENAME vibro-events-to-csv)
install(PROGRAMS scripts/auto_to_csv.py DESTINATION ${CMAKE_INSTALL_BINDIR} RENAME vibro-auto-to-csv)
install(DIRECTORY data/benchmarks DESTINATION ${CMAKE_INSTALL_DATADIR}/vibro)

set(VIBRO_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/vibro)
install(EXPORT vibroTargets NAMESPACE vibro:: DESTINATION ${VIBRO_CMAKE_DIR})
configure_package_config_file(cmake/vibroConfig.cmake.in ${PROJECT_BINARY_DIR}/vibroConfig.cmake
                              INSTALL_DESTINATION ${VIBRO_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vibroConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vibroConfig.cmake ${PROJECT_BINARY_DIR}/vibroConfigVersion.cmake
        DESTINATION ${VIBRO_CMAKE_DIR})
