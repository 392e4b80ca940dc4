// The stages of pick_candidates (plr/actions/instantiate.hpp): scene queries
// once per call; for each box of the action's region the plate poses
// generated on its faces, each pose passed through the filters, the best
// grip made a candidate; the candidates ranked. Private to the action
// library.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <tuple>
#include <unordered_set>
#include <utility>
#include <vector>

#include "footprint.hpp"
#include "plr/actions/instantiate.hpp"

namespace plr::actions::pick {

inline constexpr double kMargin = 0.03;     // m, footprint shrink and clearances
inline constexpr double kClearance = 0.02;  // m, the plate's distance to boxes it must not touch
// m, the plate's lowest edge above the floor: its bottom row of cups then
// seals on a box 9.5 cm high lying flat on the floor.
inline constexpr double kFloorGap = 0.015;
inline constexpr double kSlide = 0.05;   // m, steps of the plate off the face's centre
inline constexpr double kCovered = 0.1;  // m, the plate's centre stays this far inside the face
// m, the nearest pre-grasp: the plate comes down between the face and
// what stands in front of it.
inline constexpr double kMinPregrasp = 0.08;
inline constexpr double kProud =
    0.015;  // m a neighbour may stand out of the face (cups reach 2 cm)
// rad: a face tilted further than this from the vertical is not taken (the
// cups seal up to about 0.26 rad).
inline constexpr double kMaxFaceTilt = 0.2;
inline constexpr double kSquare = 0.03;  // rad: faces turned less than this are taken square
// rad: the furthest off the trailer's axis a face is approached (the wrist
// turns the plate that far).
inline constexpr double kMaxSideFace = 1.2;
// m past the cups' reach at which a face still counts as sealed on: a
// settled box leans a little, and a box outside the region the plate might
// take must keep the pose from being chosen.
inline constexpr double kSealMargin = 0.01;
// m: the highest lift off a tilted support (a box sunk deeper into what is
// under it is not pulled out), and what it clears the support's top by
// beyond kClearance.
inline constexpr double kMaxLift = 0.15;
// m between a box's top and the bottom of one resting on it (a settled stack).
inline constexpr double kStacked = 0.03;
inline constexpr double kLiftSlack = 0.005;
// Boxes of a wall that may rest, unsealed, on a group the plate takes: one
// rides on the load's top as it is lifted and pulled out (more would topple
// off it), which is what makes a wall's third row from the top a pick.
inline constexpr std::size_t kMaxRiders = 1;

// The box axis nearest the vertical.
int up_axis(const Eigen::Matrix3d& R);

// ---- Scene queries -------------------------------------------------------

// A side face of a box: of its horizontal axes, the one nearest the
// trailer's axis gives the face's normal and the plate's yaw (the wrist
// turns the plate square to it).
struct Face {
  Eigen::Vector3d n, lateral, centre;  // n horizontal, into the trailer
  double half_d = 0, half_w = 0, half_up = 0;
};

// What every candidate of one call is computed from, indexed as world.boxes.
struct PickScene {
  const sim::World& world;
  std::unordered_set<std::uint32_t> wall, front;  // first wall, front pile
  std::vector<sim::Bounds> bounds;
  std::vector<Polygon> outline;
  // The square face of each wall or pile box; none for a box tilted on an
  // edge, or outside the structure in front.
  std::vector<std::optional<Face>> faces;
  // Boxes of the first wall or front pile of the action's height class (a
  // box's top against the wall or pile thresholds) and third of the width.
  std::vector<bool> in_region;
  // The nearest box the lowered nose must stay short of: not one above the
  // nose (lying on the robot's arm, or leaning out over it), nor one lying
  // on the robot, which rides along with it (A1 s2: a box left on the arm
  // after a shake kept the base 2.5 m short of everything).
  double nearest = 0;
  double plate_depth = 0;  // the plate link's body behind its suction surface

  std::size_t size() const { return bounds.size(); }
  // Of the first wall or the front pile.
  bool in_front(std::size_t j) const;
};

PickScene query_scene(const sim::World& world, const sim::SceneAnalysis& scene, sim::Action action,
                      const sim::ObservationParams& obs, const sim::RobotModel& robot,
                      const Geometry& g, const sim::JointVector& current);

// ---- Generate ------------------------------------------------------------

// The face square to the robot, then the other side face of a box turned
// well off the trailer's axis where it still looks towards the robot (at
// most kMaxSideFace off the axis).
std::vector<Face> faces_to_try(const PickScene& s, std::size_t i);

// The boxes of the wall or pile stacked on box i, each resting on it or on
// one of them (those the plate does not seal on keep it in place).
std::vector<bool> stacked_on(const PickScene& s, std::size_t i);

// A face of box `box` the plate is put on.
struct Approach {
  std::size_t box = 0;
  Face face;
  bool alternative = false;  // not the square face: the box is taken alone
  double yaw = 0;            // the plate's, square to the face
  double ylim = 0;           // the plate centre's |y| that keeps its body inside the trailer
  Eigen::Vector3d point;     // the face's centre, its height kept off floor and ceiling
  // The face box j is sealed on through this approach.
  const Face& face_of(const PickScene& s, std::size_t j) const {
    return j == box ? face : *s.faces[j];
  }
};
Approach approach(const PickScene& s, const Geometry& g, std::size_t i, const Face& f,
                  bool alternative);

// Plate offsets (across, up) from the face's centre, in the order tried: on
// the face, then centred on its edges, where it may take the neighbours
// there too; after a failed grip (`fewer`), half a cup pitch off centre.
std::vector<std::pair<double, double>> plate_offsets(const Geometry& g, const Face& f,
                                                     double half_h, bool fewer);

// The plate's centre at an offset, inside the trailer and off the floor.
Eigen::Vector3d plate_at(const sim::World& world, const Geometry& g, const Approach& a, double dy,
                         double dz);

// Cups whose whole rim lies on box j's face with the plate's centre at p.
int cups_on(const PickScene& s, const Geometry& g, const Approach& a, std::size_t j,
            const Eigen::Vector3d& p);

// ---- Filters -------------------------------------------------------------

// Why a pose or a box is not taken; worded (to_string) only when asked for.
struct Refusal {
  enum class Kind { kNoFace, kProud, kNoRoom, kNoCup, kRestsOn, kInTheWay, kUnreachable };
  Kind kind = Kind::kNoFace;
  std::uint32_t box = 0, of = 0;  // the box in the way; the moving box it is in the way of
  double base_x = 0;              // kUnreachable: the base position tried
};
std::string to_string(const Refusal& r);

// What stands in the plate's corridor (its outline along the face's normal)
// at p: what reaches the face stops the plate short of it, `back` from it;
// what stands further out leaves it `room` before the face for the
// pre-grasp (the plate's body stands behind its surface).
struct Corridor {
  double back = 0, room = 0;
  std::optional<std::size_t> proud, before;  // the boxes that set them
};
Corridor corridor(const PickScene& s, const Geometry& g, const Approach& a,
                  const Eigen::Vector3d& p);
// A neighbour standing out further than the cups reach, or too little room.
std::optional<Refusal> corridor_refusal(const PickScene& s, const Geometry& g, const Corridor& c);

// Box i and every other box of the region whose face the cups reach from
// `surface` (with a margin: a settled box may lean) and that whole cups
// cover, and the boxes stacked on box i that they cover too: the stack
// comes out together. With the cups on each. An alternative face takes the
// box alone.
struct Sealed {
  std::vector<std::size_t> group;  // the box first
  std::vector<int> cups;
};
Sealed sealed_group(const PickScene& s, const Geometry& g, const Approach& a,
                    const std::vector<bool>& stacked, const Eigen::Vector3d& p,
                    const Eigen::Vector3d& surface, int own_cups);

// How high the group is lifted off what it rests on (and over the lowered
// nose) before it comes out; lifted clear of a tilted top it rests on.
double lift_height(const PickScene& s, const Geometry& g, const std::vector<std::size_t>& group);

// How far the group and the plate (its centre at p) can rise and stay
// kClearance under the ceiling: a carton of a ceiling-high wall lifted
// 5 cm pressed into it, and the cups let go (D2: 1,080 N on 1,080).
double ceiling_room(const PickScene& s, const Geometry& g, const std::vector<std::size_t>& group,
                    const Eigen::Vector3d& p);

// The boxes resting on `group` that may ride on it, unsealed, as it comes
// out: upright wall boxes, at most kMaxRiders, each resting on the group
// alone and with its centre over it (else it stays behind, or tips off
// while the load is lifted). None where any other box rests on the group:
// it keeps the group in place.
std::vector<std::size_t> riders_on(const PickScene& s, const std::vector<std::size_t>& group,
                                   double lift);

// The first box other than `group`'s in the space over `area` from z0 to z1.
// Outlines that only touch (flush neighbours) do not count: kMargin of
// overlap does. Unless `leaning_too`, a box tilted on an edge does not
// count: nothing can pick it, and it slides off what comes out under it.
std::optional<std::size_t> in_the_way(const PickScene& s, const std::vector<std::size_t>& group,
                                      const Polygon& area, double z0, double z1, bool leaning_too);

// Lifted, nothing may stand over a moving box; pulled out `out_depth` along
// -n, each (it may be wider than the plate) passes over what stands in
// front of it. Neighbours beside it, flush with it, are not in the way.
std::optional<Refusal> way_out_refusal(const PickScene& s, const std::vector<std::size_t>& moving,
                                       double lift, double out_depth, const Eigen::Vector3d& n);

// The plate poses of a candidate the arm cannot reach from its base.
std::optional<Refusal> reach_refusal(const sim::RobotModel& robot, const PickCandidate& c,
                                     const sim::JointVector& current);

// ---- Choose and rank ---------------------------------------------------------

// A plate pose that passed every filter.
struct Grip {
  std::vector<std::size_t> group;  // the box first
  std::vector<std::size_t> riders;
  std::vector<int> cups;
  Eigen::Vector3d at_face;
  double back = 0;      // plate surface to the face at the grasp
  double pregrasp = 0;  // plate to the face before the approach
  double lift = 0, out_depth = 0;
};

// More boxes at once first, then more cups on the box that has the fewest
// (the cups' force is shared by cups), then more in all; after a failed
// grip (`fewer`), fewer boxes and more cups on the box itself. A load with
// nothing riding on it first. Greater is better.
std::tuple<bool, int, int, int> grip_rank(const Grip& grip, bool fewer);

// Of the poses the approach's offsets generate, the best that passes the
// filters; nullopt, and in `refused` (if given) why the first pose refused
// was, when none does.
std::optional<Grip> best_grip(const PickScene& s, const Geometry& g, const Approach& a,
                              const std::vector<bool>& stacked, bool fewer,
                              std::optional<Refusal>* refused);

// The grip as a candidate: its plate poses, valves and base position.
PickCandidate make_candidate(const PickScene& s, const Geometry& g, const Approach& a,
                             const Grip& grip);

struct Ranked {
  PickCandidate c;
  double x_bin, top, centre_distance;
};
// Near the robot first (0.2 m bins from `nearest`), then high up, then
// nearest the trailer's axis.
Ranked ranked(const PickScene& s, std::size_t i, PickCandidate c);
// The candidates best first, at most max_count; a group found from each of
// its boxes is one candidate.
std::vector<PickCandidate> rank(std::vector<Ranked> ranked, std::size_t max_count);

}  // namespace plr::actions::pick
