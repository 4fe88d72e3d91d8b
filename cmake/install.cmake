# The svokit CMake package: `find_package(svokit)` then `target_link_libraries(x svokit::svokit)`,
# or `find_package(svokit COMPONENTS reader)` and svokit::reader alone; and svokit-reader.pc for
# pkg-config. Included from the top-level CMakeLists.txt after lib/ and apps/ have declared their
# install rules.
include(CMakePackageConfigHelpers)

set(SVOKIT_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/svokit)
# Two export sets: a reader-only consumer loads the reader's targets alone, which name no
# dependency of the build stages.
install(EXPORT svokitReaderTargets NAMESPACE svokit:: DESTINATION ${SVOKIT_CMAKE_DIR})
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

# pkg-config: paths relative to the .pc file's own folder, so the prefix may move.
file(RELATIVE_PATH SVOKIT_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
string(REGEX REPLACE "/$" "" SVOKIT_PC_TO_PREFIX "${SVOKIT_PC_TO_PREFIX}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/svokit-reader.pc.in
               ${CMAKE_CURRENT_BINARY_DIR}/svokit-reader.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/svokit-reader.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
