# ROS 1 from Debian's packages (ros-core-dev, librosbag-dev, libtf2-msgs-dev; scripts/install-deps.sh):
# the ROS transport, rosbag in and out (docs/ros.md). Debian ships ROS 1's libraries without catkin's
# CMake configuration in a usable form (roscpp's find_package needs ament's Python), so they are found
# through pkg-config and by name, and the project's messages (src/ros1/msg) are generated with
# Debian's gencpp at build time.
find_package(PkgConfig QUIET)
set(ROTORGUARD_ROS_FOUND OFF)
if(PkgConfig_FOUND)
  pkg_check_modules(ROTORGUARD_ROSCPP QUIET roscpp rostime roscpp_serialization console_bridge)
  find_library(ROTORGUARD_ROSBAG_LIBRARY rosbag)
  find_library(ROTORGUARD_ROSBAG_STORAGE_LIBRARY rosbag_storage)
  find_library(ROTORGUARD_ROSLZ4_LIBRARY roslz4)
  find_path(ROTORGUARD_PLUGINLIB_INCLUDE pluginlib/class_loader.hpp PATH_SUFFIXES pluginlib)
  find_file(ROTORGUARD_GENCPP gen_cpp.py PATHS /usr/lib/gencpp NO_DEFAULT_PATH)
  # Debian's genmsg lives in the system Python, whichever python3 comes first on PATH.
  find_program(ROTORGUARD_ROS_PYTHON python3 PATHS /usr/bin NO_DEFAULT_PATH)
  if(ROTORGUARD_ROSCPP_FOUND AND ROTORGUARD_ROSBAG_LIBRARY AND ROTORGUARD_ROSBAG_STORAGE_LIBRARY
     AND ROTORGUARD_PLUGINLIB_INCLUDE AND ROTORGUARD_GENCPP AND ROTORGUARD_ROS_PYTHON
     AND EXISTS /usr/share/nav_msgs/msg/Odometry.msg AND EXISTS /usr/include/tf2_msgs/TFMessage.h)
    set(ROTORGUARD_ROS_FOUND ON)
  endif()
endif()
