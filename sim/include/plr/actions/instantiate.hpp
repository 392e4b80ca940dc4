// Turning abstract actions into concrete goals: pick points, base positions,
// plate poses and sweep depths, from the perceived world W. Pure geometry, no
// bus; the executor node turns these into planner queries.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "plr/sim/observation.hpp"
#include "plr/sim/robot_model.hpp"
#include "plr/sim/strategy.hpp"
#include "plr/sim/suction_plate.hpp"

namespace plr::actions {

// Robot dimensions the instantiation relies on (docs/notes-planner.md).
struct Geometry {
  double conveyor_length = 1.0;     // nose hinge (at base_x) to conveyor end
  double scoop_lip = 0.06;          // lip the physics adds past the scoop's end near the floor
  double arm_yaw_offset = 0.45;     // arm_1 axis behind base_x
  double plate_half_width = 0.25;   // plate extent along y / 2
  double plate_half_height = 0.2;   // plate extent along z / 2
  double pick_reach = 1.5;          // preferred horizontal arm_1-axis-to-plate distance
  double pregrasp_distance = 0.25;  // plate stand-off before the approach
  double grasp_gap = 0.005;         // plate to box face at the grasp (suction reaches 2 cm)
  double retract_lift = 0.05;       // lift off the box below before retracting
  double nose_clearance = 0.1;      // nose tip to the nearest box
  double dropoff_bottom = 0.4;      // held box bottom over the floor, just above the lowered nose
  double dropoff_ahead = 0.5;       // held box centre ahead of base_x
  double sweep_overshoot = 0.1;     // scoop tip past the pile's far end
  double sweep_dig = 0.3;           // Sweep(mid): scoop tip into the base of the wall behind
  double sweep_high_min = 0.6;      // Sweep(high): what is in front must stand this high
  double sweep_high_in = 0.2;       // Sweep(high): scoop tip past the front face
  double nose_lift_max = 0.8;       // nose_1's upper limit
  double nose_top = 0.25;           // m, top of the lowered nose and conveyor
  // The suction cups: the robot's grid (its x runs up the plate, its y across).
  sim::SuctionPlate cups;
};

// Cups of the plate's grid whose whole rim lies on a face of half-extents
// (half_across, half_up) when the plate's centre is (across, up) off the
// face's centre.
int covered_cups(const Geometry& g, double half_across, double half_up, double across, double up);

struct PickCandidate {
  std::uint32_t box = 0;
  double base_x = 0;
  sim::PlateTarget pregrasp, grasp, retract;
  // The box is first lifted straight up, off the one it rests on, before it
  // is pulled out: dragged out, it would press into that one.
  sim::PlateTarget lift;
  int cups = 0;  // cups the grasp pose covers on the face
};

// Pick points for Pick(height, side), best first: boxes of the structure in
// front (first wall and front pile) in the action's region — their height
// class (a box's top against the wall or pile thresholds) and third of the
// width — whose front face nothing hides, on which nothing rests and that
// come out over what stands in front of them; near the robot first (0.2 m
// bins), then high up. Empty: the action is not applicable here.
// Candidates whose plate poses the arm cannot reach from their base position
// are left out. The plate is centred on the face, or as near as the corridor
// allows; for the boxes in `most_cups` (a grip failed) it goes where it covers
// the most cups, off centre if need be.
std::vector<PickCandidate> pick_candidates(const sim::World& world, const sim::SceneAnalysis& scene,
                                           sim::Action action, const sim::ObservationParams& obs,
                                           const sim::RobotModel& robot, const Geometry& g,
                                           const sim::JointVector& current, std::size_t max_count,
                                           const std::unordered_set<std::uint32_t>& most_cups = {});

// Where the plate may release held boxes over the nose, for a base at
// base_x, the plate facing forward: reachable places, best first, at most
// max_count.
std::vector<sim::PlateTarget> dropoff_targets(const sim::World& world,
                                              const std::vector<std::uint32_t>& held,
                                              const sim::RobotModel& robot, const Geometry& g,
                                              const sim::JointVector& at, std::size_t max_count);

// Whether the plate, starting at `from`, can follow straight lines through
// each of `through` in turn with the arm's IK on one branch all the way (no
// joint jumping between 1 cm steps): what the planner's straight-line mode
// (M4) needs. An IK solution for a pre-grasp that fails this leads into an
// approach or retract that cannot be planned.
bool follows_lines(const sim::RobotModel& robot, const sim::JointVector& from,
                   const std::vector<sim::PlateTarget>& through);

// The three sweeps do different things:
//   Sweep(low)   the floor layer of the front pile: the scoop flat on the
//                floor, as far as the boxes lying on the floor reach;
//   Sweep(mid)   deeper: the scoop flat, through the whole front pile and
//                `dig` into the base of the wall behind it, so that what
//                stands on the pulled-out boxes comes down;
//   Sweep(high)  the nose raised to the upper part of what is in front,
//                driven in, then lowered there: it pulls boxes down onto the
//                scoop and the floor.
struct SweepPlan {
  double start_base_x = 0;           // where the nose is set before driving in
  double end_base_x = 0;             // base at the end of the drive in
  double lift = 0;                   // nose_1 (carriage height) during the drive in
  bool lower_at_end = false;         // lower the nose to the floor before backing up
  std::vector<std::uint32_t> swept;  // the boxes the scoop drives through
};

// nullopt when the sweep has nothing to act on (Sweep(low): no pile box on
// the floor; Sweep(mid): neither pile nor wall in front; Sweep(high): nothing
// in front higher than `high_min`). The scoop stops short of the trailer's
// front wall.
std::optional<SweepPlan> sweep_plan(const sim::World& world, const sim::SceneAnalysis& scene,
                                    sim::Action action, const Geometry& g, double scoop_extension,
                                    const sim::JointVector& current);

}  // namespace plr::actions
