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
  double base_length = 1.5;         // base_link behind base_x (its rear face)
  double base_half_width = 0.65;    // base_link across the trailer, each side of its axis
  // The suction cups: the robot's grid (its x runs up the plate, its y across).
  sim::SuctionPlate cups;
  // The plate's outline is the cup field's.
  double plate_half_width() const { return cups.extent.y() / 2; }   // along y
  double plate_half_height() const { return cups.extent.x() / 2; }  // along z
};

// Cups of the plate's grid whose whole rim lies on a face of half-extents
// (half_across, half_up) when the plate's centre is (across, up) off the
// face's centre.
int covered_cups(const Geometry& g, double half_across, double half_up, double across, double up);

// Ids of the boxes within 2 cm of the box shapes' bounds of the robot's links
// at q: of the links named, or of all when `links` is empty.
std::vector<std::uint32_t> boxes_touching(const sim::World& world, const sim::RobotModel& robot,
                                          const sim::JointVector& q,
                                          const std::vector<std::string>& links = {});

// Boxes lying on the robot: off the trailer's floor, not held, and touching
// one of its links with nothing but the robot under them (fallen onto the
// arm, or onto the nose and not carried off), or with a link other than the
// nose's under them (dragged onto the arm, half on the wall they came from),
// or resting only on such boxes. They ride along with the robot and are not
// part of what stands in front of it.
std::vector<std::uint32_t> boxes_on_robot(const sim::World& world, const sim::RobotModel& robot,
                                          const sim::JointVector& q,
                                          const std::vector<std::uint32_t>& held = {});

// Whether the box lies wholly behind the robot's front edge (base_x at q):
// fallen beside or behind the base, where no action reaches it and the base
// cannot get past it.
bool behind_robot(const sim::Box& box, const sim::JointVector& q);

// `world` without the boxes named.
sim::World without(const sim::World& world, const std::vector<std::uint32_t>& ids);

// Whether the vertical plate can seal on a side face of the box: it stands
// on a face, not tilted on an edge.
bool has_sealable_face(const sim::Box& box);

// Boxes with no face the plate seals on that touch (within 2 cm of their
// bounds) one of `group`: tilted, leaning on it. pick_candidates does not
// count them as resting on the group (they slide off what comes out under
// them), so its lift and pull-out push them aside rather than avoid them.
std::vector<std::uint32_t> leaning_on(const sim::World& world,
                                      const std::vector<std::uint32_t>& group);

// Boxes resting on the held load (within 3 cm above a held box's top, over
// it): they ride along with it, and are no obstacle to its moves.
std::vector<std::uint32_t> boxes_on_load(const sim::World& world,
                                         const std::vector<std::uint32_t>& held);

struct PickCandidate {
  std::uint32_t box = 0;  // the box the plate is put on
  // Every box the plate seals on at the grasp, `box` first, all in the
  // action's region: they come out together.
  std::vector<std::uint32_t> boxes;
  std::vector<int> box_cups;  // cups on each of `boxes`
  // Wall boxes resting on `boxes` that the plate does not seal on: they ride
  // on the load as it comes out (or fall off it where the physics puts
  // them), and weigh on the cups. A candidate with riders comes after every
  // candidate without.
  std::vector<std::uint32_t> riders;
  double base_x = 0;
  sim::PlateTarget pregrasp, grasp, retract;
  // The boxes are first lifted straight up, off what they rest on, before
  // they are pulled out: dragged out, they would press into it.
  sim::PlateTarget lift;
  int cups = 0;  // cups the grasp pose covers on the face of `box`
  // The plate's cup valves at the grasp (sim::SuctionPlate's order): open
  // over the faces of `boxes`, closed elsewhere, so that a neighbour of
  // another region under the plate is not taken.
  std::vector<bool> cups_open;
};

// Pick points for Pick(height, side), best first: boxes of the structure in
// front (first wall and front pile) in the action's region — their height
// class (a box's top against the wall or pile thresholds) and third of the
// width — whose front face nothing hides; near the robot first (0.2 m
// bins), then high up. Empty: the action is not applicable here.
// The plate goes on a box's face, or on its edges where it seals on the
// neighbours there too: a candidate takes every box the plate seals on, and
// the cups over a box outside the region stay closed.
// Nothing but the group may rest on the group, and the group comes out over
// what stands in front of it. Of the poses the corridor allows, the one
// that takes the most boxes; for the boxes in `most_cups` (a grip failed)
// the fewest boxes and the most cups on the box, off centre if need be.
// Candidates whose plate poses the arm cannot reach from their base
// position are left out; a group found from several of its boxes is one
// candidate.
// A box of the region that gives no candidate, and why (the plate centred
// on its face: what is in the way, or that the arm cannot reach it).
struct PickRejection {
  std::uint32_t box = 0;
  std::string why;
};

std::vector<PickCandidate> pick_candidates(const sim::World& world, const sim::SceneAnalysis& scene,
                                           sim::Action action, const sim::ObservationParams& obs,
                                           const sim::RobotModel& robot, const Geometry& g,
                                           const sim::JointVector& current, std::size_t max_count,
                                           const std::unordered_set<std::uint32_t>& most_cups = {},
                                           std::vector<PickRejection>* rejected = nullptr);

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
                                    sim::Action action, const Geometry& g, double scoop_extension);

}  // namespace plr::actions
