#include "plr/search/grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace plr::search {
namespace {

[[noreturn]] void fail(const std::string& path, const std::string& cause) {
  throw std::runtime_error(path + ": " + cause);
}

constexpr double kSqrt2 = 1.4142135623730951;

}  // namespace

GridMap load_grid_map(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  GridMap map;
  std::string word;
  // Header: "type octile", "height H", "width W", "map" in any order.
  while (in >> word && word != "map") {
    if (word == "height") {
      in >> map.height;
    } else if (word == "width") {
      in >> map.width;
    } else if (word == "type") {
      in >> word;
    } else {
      fail(path, "unexpected header word '" + word + "'");
    }
  }
  if (word != "map") fail(path, "no 'map' line");
  if (map.width <= 0 || map.height <= 0) fail(path, "missing or bad width/height");
  map.passable.assign(static_cast<std::size_t>(map.width) * map.height, 0);
  std::string row;
  std::getline(in, row);  // rest of the "map" line
  for (int y = 0; y < map.height; ++y) {
    if (!std::getline(in, row)) fail(path, "map ends at row " + std::to_string(y));
    if (!row.empty() && row.back() == '\r') row.pop_back();
    if (static_cast<int>(row.size()) < map.width)
      fail(path, "row " + std::to_string(y) + " is short");
    for (int x = 0; x < map.width; ++x) {
      const char c = row[static_cast<std::size_t>(x)];
      map.passable[static_cast<std::size_t>(y) * map.width + x] =
          (c == '.' || c == 'G' || c == 'S') ? 1 : 0;
    }
  }
  return map;
}

std::vector<GridQuery> load_scenario(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::vector<GridQuery> out;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line.rfind("version", 0) == 0) continue;
    std::istringstream ss(line);
    int bucket = 0, w = 0, h = 0;
    std::string map_name;
    GridQuery q;
    if (!(ss >> bucket >> map_name >> w >> h >> q.start_x >> q.start_y >> q.goal_x >> q.goal_y >>
          q.optimal)) {
      fail(path, "line " + std::to_string(line_no) + ": expected 9 fields");
    }
    out.push_back(q);
  }
  return out;
}

void GridGraph::successors(StateId s, std::vector<Successor>& out) {
  const int x = s % map_.width, y = s / map_.width;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if ((dx == 0 && dy == 0) || !map_.free(x + dx, y + dy)) continue;
      if (dx != 0 && dy != 0) {
        if (!map_.free(x + dx, y) || !map_.free(x, y + dy)) continue;
        out.push_back({id(x + dx, y + dy), kSqrt2});
      } else {
        out.push_back({id(x + dx, y + dy), 1.0});
      }
    }
  }
}

double OctileHeuristic::estimate(StateId s) {
  const int dx = std::abs(s % width_ - gx_), dy = std::abs(s / width_ - gy_);
  return dx + dy + (kSqrt2 - 2.0) * std::min(dx, dy);
}

}  // namespace plr::search
