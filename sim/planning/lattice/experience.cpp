#include "experience.hpp"

#include <cstdlib>

namespace plr::planning {

void ExperienceStore::add(std::vector<JointVector> path) {
  if (path.size() < 2 || max_paths_ == 0) return;
  paths_.push_back(std::move(path));
  while (paths_.size() > max_paths_) paths_.pop_front();
}

ExperienceGraph::ExperienceGraph(
    const ExperienceStore& store, const JointVector& start, const std::vector<int>& planned,
    double weight, const std::function<double(const JointVector&, const JointVector&)>& pair_time,
    const std::function<double(const JointVector&)>& to_goal)
    : weight_(weight), pair_time_(pair_time) {
  for (std::size_t p = 0; p < store.paths().size(); ++p) {
    first_.push_back(static_cast<std::int32_t>(nodes_.size()));
    const auto& path = store.paths()[p];
    for (std::size_t i = 0; i < path.size(); ++i) {
      // The joints this query does not plan stay where its start has them.
      JointVector q = start;
      for (int j : planned) q[j] = path[i][j];
      nodes_.push_back({q, static_cast<std::int32_t>(p), static_cast<std::int32_t>(i), 0.0});
    }
  }
  first_.push_back(static_cast<std::int32_t>(nodes_.size()));
  segment_free_.assign(nodes_.size(), -1);

  // Dijkstra towards the goal over the complete graph on the nodes: a stored
  // segment costs its time, any other move w_E times the heuristic. A few
  // hundred nodes at most, so the O(n^2) array version.
  const std::size_t n = nodes_.size();
  std::vector<double> dist(n);
  std::vector<bool> done(n, false);
  for (std::size_t i = 0; i < n; ++i) dist[i] = weight_ * to_goal(nodes_[i].q);
  for (std::size_t round = 0; round < n; ++round) {
    std::size_t u = n;
    for (std::size_t i = 0; i < n; ++i) {
      if (!done[i] && (u == n || dist[i] < dist[u])) u = i;
    }
    done[u] = true;
    for (std::size_t v = 0; v < n; ++v) {
      if (done[v]) continue;
      const bool along =
          nodes_[u].path == nodes_[v].path && std::abs(nodes_[u].index - nodes_[v].index) == 1;
      const double t = pair_time_(nodes_[v].q, nodes_[u].q);
      const double c = along ? t : weight_ * t;
      if (dist[u] + c < dist[v]) dist[v] = dist[u] + c;
    }
  }
  for (std::size_t i = 0; i < n; ++i) nodes_[i].h = dist[i];
}

std::int32_t ExperienceGraph::node_at(std::int32_t path, std::int32_t index) const {
  if (index < 0) return -1;
  const std::int32_t id = first_[static_cast<std::size_t>(path)] + index;
  return id < first_[static_cast<std::size_t>(path) + 1] ? id : -1;
}

ExperienceGraph::Estimate ExperienceGraph::estimate(const JointVector& q, double h_goal) const {
  Estimate e{weight_ * h_goal, -1};
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    if (nodes_[i].h >= e.h) continue;
    const double h = weight_ * pair_time_(q, nodes_[i].q) + nodes_[i].h;
    if (h < e.h) e = {h, static_cast<std::int32_t>(i)};
  }
  return e;
}

}  // namespace plr::planning
