# `cmake --install build --prefix P` installs the library (core/ and solvers/:
# the triadcal_* static libraries), their headers under P/include/triadcal/ at
# the paths the sources use (include/triadcal/core/model/...), the `triadcal`
# binary, the Python module (python/CMakeLists.txt) and a CMake package:
# find_package(triadcal) gives triadcal::triadcal, every installed library
# with its include path and dependencies. The command's own libraries (tools/:
# report, batch, distribution, declared INTERNAL) are not installed: what the
# commands print and write is no library API, and only distribution calls MPI.
include(CMakePackageConfigHelpers)

get_property(triadcal_installed_modules GLOBAL PROPERTY TRIADCAL_INSTALLED_MODULES)
add_library(triadcal_library INTERFACE)
target_link_libraries(triadcal_library INTERFACE ${triadcal_installed_modules})
set_target_properties(triadcal_library PROPERTIES EXPORT_NAME triadcal)
add_library(triadcal::triadcal ALIAS triadcal_library)

install(TARGETS triadcal_library EXPORT triadcalTargets)
install(TARGETS triadcal RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

# The package's config looks for MPI only when an installed library links it
# (none does today: TRIADCAL_PACKAGE_NEEDS_MPI is OFF whether or not the
# binary was built with MPI).
get_property(TRIADCAL_PACKAGE_NEEDS_MPI GLOBAL PROPERTY TRIADCAL_INSTALLED_NEEDS_MPI)
if(NOT TRIADCAL_PACKAGE_NEEDS_MPI)
  set(TRIADCAL_PACKAGE_NEEDS_MPI OFF)
endif()

set(triadcal_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/triadcal)
install(EXPORT triadcalTargets NAMESPACE triadcal:: DESTINATION ${triadcal_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/triadcalConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/triadcalConfig.cmake
                              INSTALL_DESTINATION ${triadcal_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/triadcalConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/triadcalConfig.cmake
              ${PROJECT_BINARY_DIR}/triadcalConfigVersion.cmake
        DESTINATION ${triadcal_cmake_dir})
