// The ARA* lattice planner, the paper's: anytime search over a state lattice
// of motion primitives, plus adaptive primitives that snap to the goal.
//
//   auto config = plr::planning::LatticeConfig::from_file(
//       plr::sim::shipped_file("robots/unloader_lattice.yaml"));
//   plr::planning::LatticePlanner planner(*config);
//   plr::planning::PlanResult r = planner.plan(query, checker);
//
// M1/M2/M3/M5 run ARA* on the joint lattice (ε from the query's schedule,
// improved while improve_time_s allows), M4 runs A* along the plate's line.
// Search memory is kept between queries, so one planner per thread.
//
// With experience (the lattice file's `experience: true`, or
// set_experience()), the solved paths of M1 and M2 queries are kept and the
// next searches of the mode are pulled toward them (an experience graph,
// lattice/experience.hpp). Kept per planner, for one trailer: whoever loads
// a new world calls clear_experience(), and a checker on another trailer
// part clears it too. Answers then depend on the queries before, so offline
// work that must be a function of the state alone leaves it off.
#pragma once

#include <cstdint>
#include <map>
#include <memory>

#include "plr/planning/lattice_config.hpp"
#include "plr/planning/planner.hpp"

namespace plr::planning {

class ExperienceStore;

class LatticePlanner final : public Planner {
 public:
  explicit LatticePlanner(LatticeConfig config);
  ~LatticePlanner() override;

  std::string name() const override { return "arastar"; }
  const LatticeConfig& config() const { return config_; }

  void set_experience(bool enabled);
  bool experience() const { return config_.experience.enabled; }
  // Forgets the stored paths (a new trailer).
  void clear_experience();
  // Paths stored for a mode.
  std::size_t experience_paths(PlanMode mode) const;

 protected:
  PlanResult do_plan(const PlanQuery& query, sim::CollisionChecker& checker) override;

 private:
  LatticeConfig config_;
  std::unique_ptr<search::AraStar> search_;
  std::map<PlanMode, std::unique_ptr<ExperienceStore>> experience_;
  std::uint64_t trailer_ = 0;  // CollisionChecker::trailer_serial() of the stored paths
};

}  // namespace plr::planning
