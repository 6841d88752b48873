# ROS 2 bags (src/flowfusion/io/ros2_recording.cpp: MCAP and rosbag2 sqlite files) with our own
# readers over Debian's libzstd-dev, liblz4-dev (MCAP chunks) and libsqlite3-dev (.db3). Without
# them the build still works and opening a ROS 2 bag says how to enable it. Sets
# FLOWFUSION_ROS2BAG_FOUND, _INCLUDE_DIRS, _LIBRARIES and _DEFINES (FLOWFUSION_HAVE_ROS2BAG).
option(FLOWFUSION_WITH_ROS2BAG "Read ROS 2 bags when libzstd-dev, liblz4-dev and libsqlite3-dev are installed" ON)
set(FLOWFUSION_ROS2BAG_FOUND OFF)
if(FLOWFUSION_WITH_ROS2BAG)
  find_path(FLOWFUSION_ZSTD_INCLUDE zstd.h)
  find_library(FLOWFUSION_ZSTD_LIB zstd)
  find_path(FLOWFUSION_LZ4_INCLUDE lz4frame.h)
  find_library(FLOWFUSION_LZ4_LIB lz4)
  find_path(FLOWFUSION_SQLITE3_INCLUDE sqlite3.h)
  find_library(FLOWFUSION_SQLITE3_LIB sqlite3)
  if(FLOWFUSION_ZSTD_INCLUDE AND FLOWFUSION_ZSTD_LIB AND FLOWFUSION_LZ4_INCLUDE AND FLOWFUSION_LZ4_LIB
     AND FLOWFUSION_SQLITE3_INCLUDE AND FLOWFUSION_SQLITE3_LIB)
    set(FLOWFUSION_ROS2BAG_FOUND ON)
    set(FLOWFUSION_ROS2BAG_INCLUDE_DIRS ${FLOWFUSION_ZSTD_INCLUDE} ${FLOWFUSION_LZ4_INCLUDE} ${FLOWFUSION_SQLITE3_INCLUDE})
    list(REMOVE_DUPLICATES FLOWFUSION_ROS2BAG_INCLUDE_DIRS)
    set(FLOWFUSION_ROS2BAG_LIBRARIES ${FLOWFUSION_ZSTD_LIB} ${FLOWFUSION_LZ4_LIB} ${FLOWFUSION_SQLITE3_LIB})
    set(FLOWFUSION_ROS2BAG_DEFINES FLOWFUSION_HAVE_ROS2BAG)
  endif()
endif()
if(FLOWFUSION_ROS2BAG_FOUND)
  message(STATUS "flowfusion: ROS 2 bags enabled (MCAP, .db3)")
else()
  message(STATUS "flowfusion: ROS 2 bags disabled (install libzstd-dev liblz4-dev libsqlite3-dev to read them)")
endif()
