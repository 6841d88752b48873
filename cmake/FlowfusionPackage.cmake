# Installation as a CMake package (find_package(flowfusion) -> flowfusion::flowfusion) and a
# Debian package (cpack -G DEB in the build folder).
include(CMakePackageConfigHelpers)
set(FLOWFUSION_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/flowfusion)
install(EXPORT flowfusionTargets NAMESPACE flowfusion:: DESTINATION ${FLOWFUSION_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/flowfusionConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/flowfusionConfig.cmake INSTALL_DESTINATION ${FLOWFUSION_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/flowfusionConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/flowfusionConfig.cmake ${PROJECT_BINARY_DIR}/flowfusionConfigVersion.cmake
        DESTINATION ${FLOWFUSION_CMAKE_DIR})

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME flowfusion)
set(CPACK_PACKAGE_VENDOR "flowfusion developers")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Dynamic dense RGB-D SLAM based on optical flow (library, headers, command)")
set(CPACK_PACKAGE_CONTACT "flowfusion developers <flowfusion@localhost>")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# The static libraries and headers need the dependencies' development packages; the executable
# needs their runtime libraries, which these pull in.
set(CPACK_DEBIAN_PACKAGE_DEPENDS
    "libeigen3-dev, libopencv-dev, libopencv-contrib-dev, libpcl-dev, libopen3d-dev, nlohmann-json3-dev, libspdlog-dev, libfmt-dev, libtbb-dev, python3, python3-numpy")
if(FLOWFUSION_ROSBAG_FOUND)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", librosbag-storage-dev, libsensor-msgs-dev")
endif()
if(FLOWFUSION_CERES_FOUND)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libceres-dev")
endif()
if(FLOWFUSION_ROS_NODE_FOUND)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libroscpp-dev, libmessage-filters-dev, libtf2-ros-dev, libnav-msgs-dev, libdiagnostic-updater-dev, libstd-srvs-dev")
endif()
if(FLOWFUSION_ROS2BAG_FOUND)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libzstd-dev, liblz4-dev, libsqlite3-dev")
endif()
if(FLOWFUSION_LIBDEFLATE_FOUND)
  string(APPEND CPACK_DEBIAN_PACKAGE_DEPENDS ", libdeflate-dev")
endif()
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
include(CPack)
