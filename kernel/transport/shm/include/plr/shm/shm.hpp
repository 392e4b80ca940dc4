// The shared-memory transport of the PLR kernel (kernel-internal; plug-ins
// never see it). See docs/transports.md.
#pragma once

#include "plr/shm/segments.hpp"
#include "plr/shm/service.hpp"
#include "plr/shm/topic.hpp"
#include "plr/shm/types.hpp"
#include "plr/shm/wake_latency.hpp"
