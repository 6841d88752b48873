#!/usr/bin/env bash
# Installs the Debian 12 packages flowfusion builds with (run as root, or with sudo available).
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends \
  cmake g++ make pkg-config \
  libeigen3-dev libopencv-dev libopencv-contrib-dev libpcl-dev libopen3d-dev \
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev nlohmann-json3-dev \
  libspdlog-dev libfmt-dev libtbb-dev \
  python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-distributed \
  libjs-three chromium xvfb
# ROS 1 bags (`flowfusion run FILE.bag`, `flowfusion convert`): rosbag storage and the sensor_msgs
# headers; without them flowfusion builds and says how to enable bags when given one.
$SUDO apt-get install -y -qq --no-install-recommends librosbag-storage-dev libsensor-msgs-dev
# ROS 2 bags (rosbag2 folders, .mcap, .db3): our readers need zstd and lz4 (MCAP chunks) and sqlite3;
# without them flowfusion builds and says how to enable ROS 2 bags when given one. The MCAP test
# recordings are written by the MCAP project's npm packages, which the build installs with `npm ci`
# from tests/fixtures/ros2bag/package-lock.json, and ESLint for the report page's script from
# tests/lint/package-lock.json (Node 20 and npm; the tests skip without them).
$SUDO apt-get install -y -qq --no-install-recommends libzstd-dev liblz4-dev libsqlite3-dev
# Faster loading of PNG frames (core/png_decoder.cpp); without it OpenCV decodes them, the same pixels.
$SUDO apt-get install -y -qq --no-install-recommends libdeflate-dev
# Loop closure (the keyframe pose graph): Ceres; without it flowfusion builds and runs with loop
# closure off, saying so.
$SUDO apt-get install -y -qq --no-install-recommends libceres-dev
# The ROS 1 node (`flowfusion ros`): roscpp, message_filters, tf2_ros, nav_msgs, diagnostic_updater and
# std_srvs headers (with the bag packages above); its tests start roscore and use rosbag play/record and
# rosservice (ros-core, python3-std-srvs). Without them flowfusion builds, `flowfusion ros` says how to
# enable it and the node's tests skip.
$SUDO apt-get install -y -qq --no-install-recommends ros-core libroscpp-dev libmessage-filters-dev libtf2-ros-dev \
  libnav-msgs-dev libgeometry-msgs-dev libdiagnostic-updater-dev libstd-srvs-dev python3-std-srvs
