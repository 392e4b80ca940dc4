// A Cyclone DDS participant on a ROS 2 domain (ROS_DOMAIN_ID is the DDS
// domain id), and the QoS rmw_cyclonedds gives ROS 2 endpoints by default.
#pragma once

#include <plr/expected.hpp>

#include <dds/dds.h>

#include <cstdint>

namespace plr::ros2 {

// `loopback_only`: Cyclone on "lo" without multicast, peer 127.0.0.1 (tests,
// one machine); otherwise Cyclone's own configuration (CYCLONEDDS_URI), as a
// ROS 2 process with rmw_cyclonedds_cpp has it.
plr::Expected<dds_entity_t> open_participant(std::uint32_t domain_id, bool loopback_only);

// rmw's default profile: reliable, volatile, keep last `depth`.
dds_qos_t* default_qos(std::int32_t depth = 10);
// Action status: reliable, transient local, keep last 1 (rcl_action's profile).
dds_qos_t* status_qos();

}  // namespace plr::ros2
