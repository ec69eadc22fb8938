# `cmake --install build --prefix P` installs the triadcal_* static libraries,
# their headers under P/include at the paths the sources use (core/model/...),
# the `triadcal` binary, and a CMake package: find_package(triadcal) gives
# triadcal::triadcal, every library with its dependencies.
include(CMakePackageConfigHelpers)

get_property(triadcal_modules GLOBAL PROPERTY TRIADCAL_MODULES)
add_library(triadcal_library INTERFACE)
target_link_libraries(triadcal_library INTERFACE ${triadcal_modules})
set_target_properties(triadcal_library PROPERTIES EXPORT_NAME triadcal)
add_library(triadcal::triadcal ALIAS triadcal_library)

install(TARGETS triadcal_library EXPORT triadcalTargets)
install(TARGETS triadcal RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})

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
