# Faster PNG loading (src/flowfusion/core/png_decoder.cpp) with Debian's libdeflate-dev. Without it
# the build still works and every image is decoded by OpenCV (libpng and zlib), the same pixels at
# about twice the CPU time. Sets FLOWFUSION_LIBDEFLATE_FOUND, _INCLUDE_DIRS, _LIBRARIES and _DEFINES
# (FLOWFUSION_HAVE_LIBDEFLATE).
option(FLOWFUSION_WITH_LIBDEFLATE "Decode PNG frames with libdeflate when libdeflate-dev is installed" ON)
set(FLOWFUSION_LIBDEFLATE_FOUND OFF)
if(FLOWFUSION_WITH_LIBDEFLATE)
  find_path(FLOWFUSION_LIBDEFLATE_INCLUDE libdeflate.h)
  find_library(FLOWFUSION_LIBDEFLATE_LIB deflate)
  if(FLOWFUSION_LIBDEFLATE_INCLUDE AND FLOWFUSION_LIBDEFLATE_LIB)
    set(FLOWFUSION_LIBDEFLATE_FOUND ON)
    set(FLOWFUSION_LIBDEFLATE_INCLUDE_DIRS ${FLOWFUSION_LIBDEFLATE_INCLUDE})
    set(FLOWFUSION_LIBDEFLATE_LIBRARIES ${FLOWFUSION_LIBDEFLATE_LIB})
    set(FLOWFUSION_LIBDEFLATE_DEFINES FLOWFUSION_HAVE_LIBDEFLATE)
  endif()
endif()
if(FLOWFUSION_LIBDEFLATE_FOUND)
  message(STATUS "flowfusion: PNG frames decoded with libdeflate")
else()
  message(STATUS "flowfusion: PNG frames decoded by OpenCV (install libdeflate-dev for faster loading)")
endif()
