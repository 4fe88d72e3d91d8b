# The svokit CMake package: `find_package(svokit)` then `target_link_libraries(x svokit::svokit)`.
# Included from the top-level CMakeLists.txt after lib/ and apps/ have declared their install rules.
include(CMakePackageConfigHelpers)

set(SVOKIT_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/svokit)
install(EXPORT svokitTargets NAMESPACE svokit:: DESTINATION ${SVOKIT_CMAKE_DIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/svokitConfig.cmake.in
                              ${CMAKE_CURRENT_BINARY_DIR}/svokitConfig.cmake
                              INSTALL_DESTINATION ${SVOKIT_CMAKE_DIR})
# 0.x: a minor version may change the API.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/svokitConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/svokitConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/svokitConfigVersion.cmake
        DESTINATION ${SVOKIT_CMAKE_DIR})
