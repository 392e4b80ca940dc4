// All message schemas of the SDK (generated from sdk/schemas/*.fbs).
#pragma once

#include <plr/msg/common_generated.h>
#include <plr/msg/demo_generated.h>
#include <plr/msg/driver_generated.h>
#include <plr/msg/executor_state_generated.h>
#include <plr/msg/plan_generated.h>
#include <plr/msg/simulation_generated.h>
#include <plr/msg/strategy_generated.h>
#include <plr/msg/telemetry_generated.h>
#include <plr/msg/trajectory_generated.h>
#include <plr/msg/world_generated.h>
