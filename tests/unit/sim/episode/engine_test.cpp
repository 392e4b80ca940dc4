// The episode engine: its stop rules and sources, the order observers are
// told in, the curve it records, and a lost world recovered from the last
// checkpoint to the same end as a run that lost nothing.
#include "plr/episode/engine.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "scene.hpp"

namespace plr::episode {
namespace {

using actions::testing::Fixture;
using actions::testing::options;
using actions::testing::robot;
using actions::testing::wall;

// Each hook as "<name>:<hook>[ <action number>]".
class Trace final : public Observer {
 public:
  Trace(std::string name, std::vector<std::string>& events)
      : name_(std::move(name)), events_(events) {}
  void starting(const ActionStart& a, const Episode&) override {
    add("starting " + std::to_string(a.number));
  }
  void progress(const std::string&) override { progress_ = true; }
  void recorded(const EpisodeStep&, const Episode& e) override {
    add("recorded " + std::to_string(e.actions));
  }
  void lost(const plr::Error&) override { add("lost"); }
  void restored(const Episode&) override { add("restored"); }
  void stopped(const Episode&) override { add("stopped"); }
  bool saw_progress() const { return progress_; }

 private:
  void add(const std::string& what) { events_.push_back(name_ + ":" + what); }
  std::string name_;
  std::vector<std::string>& events_;
  bool progress_ = false;
};

StrategySource hardcoded() {
  return hardcoded_source(sim::HardcodedParams{});
}

TEST(Engine, ASourceWithNoStrategyEndsTheRunWithItsReason) {
  Fixture f(wall(6.0, 2, 1));
  const actions::ActionModel model(robot(), options());
  int asked = 0;
  const StrategySource none = [&](const actions::Perceived&, const sim::SceneAnalysis&,
                                  const RunRules&) -> plr::Expected<StrategyChoice> {
    ++asked;
    return StrategyChoice{std::nullopt, "test", "nothing to do"};
  };
  EngineSettings settings;
  settings.classify_left = false;
  const auto e = run_episode(model, f.backend, none, settings);
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(asked, 1);
  EXPECT_EQ(e->stop_reason, "nothing to do");
  EXPECT_EQ(e->strategies_asked, 1u);
  EXPECT_EQ(e->actions, 0u);
  EXPECT_EQ(e->boxes_total, 2u);
  EXPECT_TRUE(e->left.empty());  // not classified
  EXPECT_EQ(e->final_world.boxes.size(), 2u);
}

TEST(Engine, ASourcesErrorEndsTheRunAndTheFiguresSoFarStay) {
  Fixture f(wall(6.0, 2, 1));
  const actions::ActionModel model(robot(), options());
  const StrategySource broken = [](const actions::Perceived&, const sim::SceneAnalysis&,
                                   const RunRules&) -> plr::Expected<StrategyChoice> {
    return plr::make_error(PLR_ERR_INTERNAL, "no library");
  };
  Engine engine(model, f.backend, broken, {});
  const auto ran = engine.run();
  ASSERT_FALSE(ran);
  EXPECT_EQ(ran.error().message, "no library");
  EXPECT_EQ(engine.episode().boxes_total, 2u);
  EXPECT_TRUE(engine.episode().stop_reason.empty());
}

// One action, then the action limit: observers told in the order given,
// each action's start before its record, the stop last; the boxes left
// classified.
TEST(Engine, ObserversAreToldInOrderAndTheActionLimitStopsTheRun) {
  Fixture f(wall(6.0, 3, 1));
  const actions::ActionModel model(robot(), options());
  std::vector<std::string> events;
  Trace a("a", events), b("b", events);
  EngineSettings settings;
  settings.limits.max_actions = 1;
  settings.observers = {&a, &b};
  const auto e = run_episode(model, f.backend, hardcoded(), settings);
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->stop_reason, "action limit (1)");
  EXPECT_EQ(e->actions, 1u);
  const std::vector<std::string> want = {"a:starting 1", "b:starting 1", "a:recorded 1",
                                         "b:recorded 1", "a:stopped",    "b:stopped"};
  EXPECT_EQ(events, want);
  EXPECT_TRUE(a.saw_progress());
  ASSERT_EQ(e->steps.size(), 1u);
  EXPECT_EQ(e->steps[0].source, "hardcoded");
  EXPECT_EQ(e->left.size(), e->boxes_total - e->boxes_unloaded);
}

// The curve ends where the run does, never goes back, and has a step for
// each box unloaded; the figures are the steps' sums.
TEST(Engine, TheCurveAndTheFiguresAreTheSteps) {
  Fixture f(wall(6.0, 3, 1));
  const actions::ActionModel model(robot(), options());
  const auto e = run_episode(model, f.backend, hardcoded());
  ASSERT_TRUE(e) << e.error().message;
  EXPECT_EQ(e->stop_reason, "trailer empty");
  const auto& curve = e->curve.points();
  ASSERT_FALSE(curve.empty());
  EXPECT_EQ(curve.back().robot_time_s, e->robot_time_s);
  EXPECT_EQ(curve.back().boxes, e->boxes_unloaded);
  for (std::size_t i = 1; i < curve.size(); ++i) {
    EXPECT_GE(curve[i].robot_time_s, curve[i - 1].robot_time_s);
    EXPECT_GE(curve[i].boxes, curve[i - 1].boxes);
  }
  double t = 0;
  std::uint32_t boxes = 0;
  for (const auto& s : e->steps) {
    t += s.outcome.robot_time_s;
    boxes += s.outcome.boxes;
  }
  EXPECT_EQ(t, e->robot_time_s);
  EXPECT_EQ(boxes, e->boxes_unloaded);
  EXPECT_EQ(e->steps.size(), e->actions);
  EXPECT_EQ(e->pick.executions + e->sweep.executions + e->not_applicable, e->actions);
}

// Wasted robot time: all of an action that unloaded nothing, only the
// planning of one that did.
TEST(Engine, WastedTimeIsTheIdleActionsAndTheOthersPlanning) {
  Fixture f(wall(6.0, 3, 2));
  const actions::ActionModel model(robot(), options());
  const auto e = run_episode(model, f.backend, hardcoded());
  ASSERT_TRUE(e) << e.error().message;
  double wasted = 0, planning = 0;
  for (const auto& s : e->steps) {
    wasted += s.outcome.boxes == 0 ? s.outcome.robot_time_s : s.outcome.plan_model_s;
    planning += s.outcome.plan_model_s;
  }
  EXPECT_DOUBLE_EQ(e->wasted_s, wasted);
  EXPECT_GT(e->wasted_s, 0.0);       // every pick plans before it moves
  EXPECT_GE(e->wasted_s, planning);  // planning is waited for, whatever it bought
  EXPECT_LT(e->wasted_s, e->robot_time_s);
  EXPECT_DOUBLE_EQ(wasted_share(*e), e->wasted_s / e->robot_time_s);
}

// The in-process backend with a simulator that dies once when told to: its
// next execute fails as a lost host's would. Restoring it repeats the run
// bit for bit (UnloaderSimulation::save).
class Flaky final : public actions::Backend, public Recovery {
 public:
  explicit Flaky(Fixture& f) : f_(f) {}
  plr::Expected<actions::Perceived> observe() override { return f_.backend.observe(); }
  plr::Expected<planning::DecodedPlanResponse> plan(const planning::PlanQuery& query,
                                                    const sim::World& world) override {
    return f_.backend.plan(query, world);
  }
  plr::Expected<actions::Executed> execute(const actions::Motion& motion) override {
    if (die_) {
      die_ = false;
      return plr::make_error(PLR_ERR_UNAVAILABLE, "host died");
    }
    return f_.backend.execute(motion);
  }
  plr::Status checkpoint() override {
    saved_ = f_.simulation.save();
    ++checkpoints;
    return {};
  }
  bool lost(const plr::Error& error) const override { return error.code == PLR_ERR_UNAVAILABLE; }
  plr::Status restore() override {
    f_.simulation.restore(*saved_);
    return {};
  }
  void die() { die_ = true; }

  int checkpoints = 0;

 private:
  Fixture& f_;
  bool die_ = false;
  std::shared_ptr<const actions::UnloaderSimulation::Saved> saved_;
};

// Kills the simulator in the middle of the second action, once.
class Killer final : public Observer {
 public:
  explicit Killer(Flaky& flaky) : flaky_(flaky) {}
  void starting(const ActionStart& a, const Episode&) override {
    if (a.number == 2 && !done_) flaky_.die();
    done_ = done_ || a.number == 2;
  }

 private:
  Flaky& flaky_;
  bool done_ = false;
};

TEST(Engine, ALostWorldIsRestoredAndTheInterruptedActionRepeated) {
  const actions::ActionModel model(robot(), options());
  auto run = [&](bool kill, std::vector<std::string>& events) {
    Fixture f(wall(6.0, 3, 1));
    Flaky flaky(f);
    Killer killer(flaky);
    Trace trace("t", events);
    EngineSettings settings;
    settings.observers = {&trace};
    if (kill) settings.observers.push_back(&killer);
    settings.recovery = &flaky;
    auto e = run_episode(model, flaky, hardcoded(), settings);
    if (e) {
      EXPECT_EQ(flaky.checkpoints, static_cast<int>(e->actions + 1));
    }
    return e;
  };
  std::vector<std::string> smooth_events, lost_events;
  const auto smooth = run(false, smooth_events);
  ASSERT_TRUE(smooth) << smooth.error().message;
  ASSERT_GE(smooth->actions, 2u);
  const auto recovered = run(true, lost_events);
  ASSERT_TRUE(recovered) << recovered.error().message;
  EXPECT_EQ(smooth->recoveries, 0u);
  EXPECT_EQ(recovered->recoveries, 1u);
  EXPECT_EQ(recovered->boxes_unloaded, smooth->boxes_unloaded);
  EXPECT_EQ(recovered->robot_time_s, smooth->robot_time_s);
  EXPECT_EQ(recovered->actions, smooth->actions);
  EXPECT_EQ(recovered->curve.points().size(), smooth->curve.points().size());
  const std::vector<std::string> around_the_loss = {"t:recorded 1", "t:starting 2", "t:lost",
                                                    "t:restored", "t:starting 2"};
  EXPECT_NE(std::search(lost_events.begin(), lost_events.end(), around_the_loss.begin(),
                        around_the_loss.end()),
            lost_events.end())
      << ::testing::PrintToString(lost_events);
}

}  // namespace
}  // namespace plr::episode
