// Writes the standard benchmark problems that are too large to keep in the
// repository, in both Cassandra (.pomdp) and POMDPX (.pomdpx) form:
//   gen_pomdp rocksample N K HALF_EFFICIENCY_DISTANCE OUT   (OUT ends in .pomdp or .pomdpx)
//   gen_pomdp tag OUT
// RockSample(n, k) follows Smith and Simmons (UAI 2004) as in Trey Smith's
// generator (the one behind the shared RockSample_4_4.pomdp): rover at
// (0, n/2), moving off the east edge earns 10 and ends, any other illegal
// move or sampling off a rock costs 100 and ends, sampling earns +-10 and
// leaves the rock bad, checking rock i reports correctly with probability
// (1 + eta) / 2, eta = 2^(-d / d0). Tag follows Pineau et al. (IJCAI 2003):
// 29 cells, the opponent moves away (0.4 along each axis) or stays.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

namespace {

using Cell = std::pair<int, int>;

// Rock positions of the published instances (x, y).
const std::map<std::pair<int, int>, std::vector<Cell>> kRocks = {
    {{4, 4}, {{3, 1}, {2, 1}, {1, 3}, {1, 0}}},
    {{5, 7}, {{1, 0}, {2, 1}, {1, 2}, {2, 2}, {4, 2}, {0, 3}, {3, 4}}},
    {{7, 8}, {{2, 0}, {0, 1}, {3, 1}, {6, 3}, {2, 4}, {3, 4}, {5, 5}, {1, 6}}},
};

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

struct RockSample {
  int n = 0;
  std::vector<Cell> rocks;
  double d0 = 20.0;
  int k() const { return static_cast<int>(rocks.size()); }
  int rock_at(int x, int y) const {
    for (int i = 0; i < k(); ++i) {
      if (rocks[static_cast<std::size_t>(i)] == Cell{x, y}) return i;
    }
    return -1;
  }
  // P(the check of rock i from (x, y) says "good" | the rock is good / bad).
  std::pair<double, double> good_reading(int i, int x, int y) const {
    const auto [rx, ry] = rocks[static_cast<std::size_t>(i)];
    const double eta = std::exp(-std::hypot(x - rx, y - ry) * std::log(2.0) / d0);
    return {(1.0 + eta) / 2.0, (1.0 - eta) / 2.0};
  }
};

std::string actions_of(const RockSample& p) {
  std::string a = "amn ame ams amw";
  for (int i = 0; i < p.k(); ++i) a += fmt::format(" ac{}", i);
  return a + " as";
}

// Cassandra form: states x, y, rock bits (rock 0 the highest bit), then st.
void write_rocksample_pomdp(const RockSample& p, std::FILE* out) {
  const int k = p.k(), n = p.n, combos = 1 << k;
  const auto name = [&](int x, int y, int r) {
    std::string s = fmt::format("s{}_{}_", x, y);
    for (int i = 0; i < k; ++i) s += (r >> (k - 1 - i)) & 1 ? '1' : '0';
    return s;
  };
  std::fprintf(out, "# RockSample(%d,%d), written by gen_pomdp\ndiscount: 0.95\nvalues: reward\n",
               n, k);
  std::fprintf(out, "actions: %s\nobservations: ogood obad\nstates:", actions_of(p).c_str());
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y)
      for (int r = 0; r < combos; ++r) std::fprintf(out, " %s", name(x, y, r).c_str());
  std::fprintf(out, " st\nstart include:");
  for (int r = 0; r < combos; ++r) std::fprintf(out, " %s", name(0, n / 2, r).c_str());
  std::fprintf(out, "\n\nT: * : st : st 1\nO: * : * : ogood 1\n");
  const int dx[4] = {0, 1, 0, -1}, dy[4] = {1, 0, -1, 0};
  const char* moves[4] = {"amn", "ame", "ams", "amw"};
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) {
      const int here = p.rock_at(x, y);
      for (int r = 0; r < combos; ++r) {
        const std::string s = name(x, y, r);
        for (int m = 0; m < 4; ++m) {
          const int nx = x + dx[m], ny = y + dy[m];
          if (nx >= n) {
            std::fprintf(out, "T: %s : %s : st 1\nR: %s : %s : * : * 10\n", moves[m], s.c_str(),
                         moves[m], s.c_str());
          } else if (nx < 0 || ny < 0 || ny >= n) {
            std::fprintf(out, "T: %s : %s : st 1\nR: %s : %s : * : * -100\n", moves[m], s.c_str(),
                         moves[m], s.c_str());
          } else {
            std::fprintf(out, "T: %s : %s : %s 1\n", moves[m], s.c_str(), name(nx, ny, r).c_str());
          }
        }
        for (int i = 0; i < k; ++i) {
          const bool good = (r >> (k - 1 - i)) & 1;
          const auto [pg, pb] = p.good_reading(i, x, y);
          const double g = good ? pg : pb;
          std::fprintf(out,
                       "T: ac%d : %s : %s 1\nO: ac%d : %s : ogood %.9f\nO: ac%d : %s : obad %.9f\n",
                       i, s.c_str(), s.c_str(), i, s.c_str(), g, i, s.c_str(), 1.0 - g);
        }
        if (here < 0) {
          std::fprintf(out, "T: as : %s : st 1\nR: as : %s : * : * -100\n", s.c_str(), s.c_str());
        } else {
          const int bit = 1 << (k - 1 - here);
          std::fprintf(out, "T: as : %s : %s 1\nR: as : %s : * : * %d\n", s.c_str(),
                       name(x, y, r & ~bit).c_str(), s.c_str(), r & bit ? 10 : -10);
        }
      }
    }
  }
}

// POMDPX form: a rover variable (cells then st) and one variable per rock.
void write_rocksample_pomdpx(const RockSample& p, std::FILE* out) {
  const int k = p.k(), n = p.n, cells = n * n;
  const auto cell = [n](int x, int y) { return fmt::format("x{}y{}", x, y); };
  std::string rover_values;
  for (int x = 0; x < n; ++x)
    for (int y = 0; y < n; ++y) rover_values += cell(x, y) + " ";
  rover_values += "st";
  std::fprintf(out, "<?xml version=\"1.0\"?>\n<!-- RockSample(%d,%d), written by gen_pomdp -->\n",
               n, k);
  std::fprintf(
      out,
      "<pomdpx version=\"0.1\" id=\"RockSample_%d_%d\">\n<Discount>0.95</Discount>\n<Variable>\n",
      n, k);
  std::fprintf(out,
               "<StateVar vnamePrev=\"rover_0\" vnameCurr=\"rover_1\" "
               "fullyObs=\"true\"><ValueEnum>%s</ValueEnum></StateVar>\n",
               rover_values.c_str());
  for (int i = 0; i < k; ++i) {
    std::fprintf(out,
                 "<StateVar vnamePrev=\"rock%d_0\" vnameCurr=\"rock%d_1\"><ValueEnum>bad "
                 "good</ValueEnum></StateVar>\n",
                 i, i);
  }
  std::fprintf(out, "<ObsVar vname=\"sensor\"><ValueEnum>ogood obad</ValueEnum></ObsVar>\n");
  std::fprintf(out, "<ActionVar vname=\"action\"><ValueEnum>%s</ValueEnum></ActionVar>\n",
               actions_of(p).c_str());
  std::fprintf(out, "<RewardVar vname=\"reward\"/>\n</Variable>\n<InitialStateBelief>\n");
  std::fprintf(out,
               "<CondProb><Var>rover_0</Var><Parent>null</Parent><Parameter "
               "type=\"TBL\"><Entry><Instance>%s</Instance>"
               "<ProbTable>1.0</ProbTable></Entry></Parameter></CondProb>\n",
               cell(0, n / 2).c_str());
  for (int i = 0; i < k; ++i) {
    std::fprintf(out,
                 "<CondProb><Var>rock%d_0</Var><Parent>null</Parent><Parameter "
                 "type=\"TBL\"><Entry><Instance>-</Instance>"
                 "<ProbTable>uniform</ProbTable></Entry></Parameter></CondProb>\n",
                 i);
  }
  std::fprintf(out, "</InitialStateBelief>\n<StateTransitionFunction>\n");
  // The rover: checks stay, moves move, illegal moves and exits end in st.
  std::fprintf(
      out, "<CondProb><Var>rover_1</Var><Parent>action rover_0</Parent><Parameter type=\"TBL\">\n");
  std::fprintf(out, "<Entry><Instance>* - -</Instance><ProbTable>identity</ProbTable></Entry>\n");
  const int dx[4] = {0, 1, 0, -1}, dy[4] = {1, 0, -1, 0};
  const char* moves[4] = {"amn", "ame", "ams", "amw"};
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) {
      for (int m = 0; m < 4; ++m) {
        const int nx = x + dx[m], ny = y + dy[m];
        const bool off = nx < 0 || ny < 0 || nx >= n || ny >= n;
        std::fprintf(out,
                     "<Entry><Instance>%s %s %s</Instance><ProbTable>1.0</ProbTable></Entry>\n",
                     moves[m], cell(x, y).c_str(), off ? "st" : cell(nx, ny).c_str());
        // Undo the identity entry above for this move.
        std::fprintf(out,
                     "<Entry><Instance>%s %s %s</Instance><ProbTable>0.0</ProbTable></Entry>\n",
                     moves[m], cell(x, y).c_str(), cell(x, y).c_str());
      }
      if (p.rock_at(x, y) < 0) {
        std::fprintf(out,
                     "<Entry><Instance>as %s -</Instance><ProbTable>%s1.0</ProbTable></Entry>\n",
                     cell(x, y).c_str(),
                     [&] {
                       std::string z;
                       for (int c = 0; c < cells; ++c) z += "0.0 ";
                       return z;
                     }()
                         .c_str());
      }
    }
  }
  std::fprintf(out, "</Parameter></CondProb>\n");
  // A rock turns bad when sampled where it lies.
  for (int i = 0; i < k; ++i) {
    const auto [rx, ry] = p.rocks[static_cast<std::size_t>(i)];
    std::fprintf(out,
                 "<CondProb><Var>rock%d_1</Var><Parent>action rover_0 rock%d_0</Parent><Parameter "
                 "type=\"TBL\">\n"
                 "<Entry><Instance>* * - -</Instance><ProbTable>identity</ProbTable></Entry>\n"
                 "<Entry><Instance>as %s * -</Instance><ProbTable>1.0 0.0</ProbTable></Entry>\n"
                 "</Parameter></CondProb>\n",
                 i, i, cell(rx, ry).c_str());
  }
  std::fprintf(out,
               "</StateTransitionFunction>\n<ObsFunction>\n<CondProb><Var>sensor</"
               "Var><Parent>action rover_1");
  for (int i = 0; i < k; ++i) std::fprintf(out, " rock%d_1", i);
  std::fprintf(out, "</Parent><Parameter type=\"TBL\">\n<Entry><Instance>*");
  for (int i = 0; i <= k; ++i) std::fprintf(out, " *");
  std::fprintf(out, " -</Instance><ProbTable>1.0 0.0</ProbTable></Entry>\n");
  for (int i = 0; i < k; ++i) {
    for (int x = 0; x < n; ++x) {
      for (int y = 0; y < n; ++y) {
        const auto [pg, pb] = p.good_reading(i, x, y);
        for (int good = 0; good < 2; ++good) {
          std::string inst = fmt::format("ac{} {}", i, cell(x, y));
          for (int j = 0; j < k; ++j) inst += j == i ? (good ? " good" : " bad") : " *";
          const double g = good ? pg : pb;
          std::fprintf(out,
                       "<Entry><Instance>%s -</Instance><ProbTable>%.9f %.9f</ProbTable></Entry>\n",
                       inst.c_str(), g, 1.0 - g);
        }
      }
    }
  }
  std::fprintf(out, "</Parameter></CondProb>\n</ObsFunction>\n<RewardFunction>\n");
  std::fprintf(out,
               "<Func><Var>reward</Var><Parent>action rover_0</Parent><Parameter type=\"TBL\">\n");
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) {
      for (int m = 0; m < 4; ++m) {
        const int nx = x + dx[m], ny = y + dy[m];
        if (nx >= n) {
          std::fprintf(out,
                       "<Entry><Instance>%s %s</Instance><ValueTable>10</ValueTable></Entry>\n",
                       moves[m], cell(x, y).c_str());
        } else if (nx < 0 || ny < 0 || ny >= n) {
          std::fprintf(out,
                       "<Entry><Instance>%s %s</Instance><ValueTable>-100</ValueTable></Entry>\n",
                       moves[m], cell(x, y).c_str());
        }
      }
      if (p.rock_at(x, y) < 0) {
        std::fprintf(out,
                     "<Entry><Instance>as %s</Instance><ValueTable>-100</ValueTable></Entry>\n",
                     cell(x, y).c_str());
      }
    }
  }
  std::fprintf(out, "</Parameter></Func>\n");
  for (int i = 0; i < k; ++i) {
    const auto [rx, ry] = p.rocks[static_cast<std::size_t>(i)];
    std::fprintf(
        out,
        "<Func><Var>reward</Var><Parent>action rover_0 rock%d_0</Parent><Parameter type=\"TBL\">"
        "<Entry><Instance>as %s -</Instance><ValueTable>-10 "
        "10</ValueTable></Entry></Parameter></Func>\n",
        i, cell(rx, ry).c_str());
  }
  std::fprintf(out, "</RewardFunction>\n</pomdpx>\n");
}

// Tag: the 29 cells, two rows of ten and a 3x3 block on columns 5-7.
std::vector<Cell> tag_cells() {
  std::vector<Cell> c;
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 10; ++x)
      if (y < 2 || (x >= 5 && x <= 7)) c.emplace_back(x, y);
  return c;
}

struct Tag {
  std::vector<Cell> cells = tag_cells();
  int count() const { return static_cast<int>(cells.size()); }
  int index(int x, int y) const {
    for (int i = 0; i < count(); ++i) {
      if (cells[static_cast<std::size_t>(i)] == Cell{x, y}) return i;
    }
    return -1;
  }
  // Robot moves: N, S, E, W; blocked moves stay.
  int move(int c, int m) const {
    static const int dx[4] = {0, 0, 1, -1}, dy[4] = {1, -1, 0, 0};
    const auto [x, y] = cells[static_cast<std::size_t>(c)];
    const int to = index(x + dx[m], y + dy[m]);
    return to < 0 ? c : to;
  }
  // The opponent at `o` flees the robot at `r`: 0.4 along each axis away
  // (split when level on that axis), 0.2 stays; blocked moves stay.
  std::map<int, double> flee(int r, int o) const {
    std::map<int, double> out;
    const auto [rx, ry] = cells[static_cast<std::size_t>(r)];
    const auto [ox, oy] = cells[static_cast<std::size_t>(o)];
    const auto go = [&](int dx, int dy, double p) {
      const int to = index(ox + dx, oy + dy);
      out[to < 0 ? o : to] += p;
    };
    if (ox > rx)
      go(1, 0, 0.4);
    else if (ox < rx)
      go(-1, 0, 0.4);
    else {
      go(1, 0, 0.2);
      go(-1, 0, 0.2);
    }
    if (oy > ry)
      go(0, 1, 0.4);
    else if (oy < ry)
      go(0, -1, 0.4);
    else {
      go(0, 1, 0.2);
      go(0, -1, 0.2);
    }
    out[o] += 0.2;
    return out;
  }
};

const char* kTagActions[5] = {"north", "south", "east", "west", "tag"};

// Cassandra form: states r<robot>_o<opponent> and r<robot>_tagged.
void write_tag_pomdp(const Tag& t, std::FILE* out) {
  const int n = t.count();
  std::fprintf(out, "# Tag, written by gen_pomdp\ndiscount: 0.95\nvalues: reward\n");
  std::fprintf(out, "actions: north south east west tag\nobservations:");
  for (int c = 0; c < n; ++c) std::fprintf(out, " at%d", c);
  std::fprintf(out, " seen\nstates:");
  for (int r = 0; r < n; ++r) {
    for (int o = 0; o < n; ++o) std::fprintf(out, " r%d_o%d", r, o);
    std::fprintf(out, " r%d_tagged", r);
  }
  std::fprintf(out, "\nstart include:");
  for (int r = 0; r < n; ++r)
    for (int o = 0; o < n; ++o) std::fprintf(out, " r%d_o%d", r, o);
  std::fprintf(out, "\n\n");
  for (int r = 0; r < n; ++r) {
    std::fprintf(out, "T: * : r%d_tagged : r%d_tagged 1\nO: * : r%d_tagged : seen 1\n", r, r, r);
    for (int o = 0; o < n; ++o) {
      std::fprintf(out, "O: * : r%d_o%d : %s 1\n", r, o,
                   r == o ? "seen" : fmt::format("at{}", r).c_str());
      for (int a = 0; a < 5; ++a) {
        if (a == 4 && r == o) {
          std::fprintf(out, "T: tag : r%d_o%d : r%d_tagged 1\nR: tag : r%d_o%d : * : * 10\n", r, o,
                       r, r, o);
          continue;
        }
        const int nr = a == 4 ? r : t.move(r, a);
        for (const auto& [no, p] : t.flee(r, o)) {
          std::fprintf(out, "T: %s : r%d_o%d : r%d_o%d %.6f\n", kTagActions[a], r, o, nr, no, p);
        }
        std::fprintf(out, "R: %s : r%d_o%d : * : * %d\n", kTagActions[a], r, o, a == 4 ? -10 : -1);
      }
    }
  }
}

// POMDPX form: robot and opponent variables (the opponent also "tagged").
void write_tag_pomdpx(const Tag& t, std::FILE* out) {
  const int n = t.count();
  std::string cells, obs;
  for (int c = 0; c < n; ++c) {
    cells += fmt::format("c{} ", c);
    obs += fmt::format("at{} ", c);
  }
  std::fprintf(out,
               "<?xml version=\"1.0\"?>\n<!-- Tag, written by gen_pomdp -->\n<pomdpx "
               "version=\"0.1\" id=\"Tag\">\n");
  std::fprintf(out, "<Discount>0.95</Discount>\n<Variable>\n");
  std::fprintf(out,
               "<StateVar vnamePrev=\"robot_0\" "
               "vnameCurr=\"robot_1\"><ValueEnum>%s</ValueEnum></StateVar>\n",
               cells.c_str());
  std::fprintf(out,
               "<StateVar vnamePrev=\"opp_0\" "
               "vnameCurr=\"opp_1\"><ValueEnum>%stagged</ValueEnum></StateVar>\n",
               cells.c_str());
  std::fprintf(out, "<ObsVar vname=\"seen\"><ValueEnum>%sseen</ValueEnum></ObsVar>\n", obs.c_str());
  std::fprintf(
      out,
      "<ActionVar vname=\"action\"><ValueEnum>north south east west tag</ValueEnum></ActionVar>\n");
  std::fprintf(out, "<RewardVar vname=\"reward\"/>\n</Variable>\n<InitialStateBelief>\n");
  std::fprintf(
      out,
      "<CondProb><Var>robot_0</Var><Parent>null</Parent><Parameter><Entry><Instance>-</Instance>"
      "<ProbTable>uniform</ProbTable></Entry></Parameter></CondProb>\n");
  std::fprintf(out,
               "<CondProb><Var>opp_0</Var><Parent>null</Parent><Parameter><Entry><Instance>-</"
               "Instance><ProbTable>");
  for (int c = 0; c < n; ++c) std::fprintf(out, "%.12f ", 1.0 / n);
  std::fprintf(out,
               "0</ProbTable></Entry></Parameter></CondProb>\n</"
               "InitialStateBelief>\n<StateTransitionFunction>\n");
  std::fprintf(out,
               "<CondProb><Var>robot_1</Var><Parent>action robot_0 opp_0</Parent><Parameter>\n");
  std::fprintf(out,
               "<Entry><Instance>tag - * -</Instance><ProbTable>identity</ProbTable></Entry>\n");
  std::fprintf(out,
               "<Entry><Instance>* - tagged -</Instance><ProbTable>identity</ProbTable></Entry>\n");
  for (int a = 0; a < 4; ++a) {
    for (int r = 0; r < n; ++r) {
      for (int o = 0; o < n; ++o) {
        std::string row;
        for (int c = 0; c < n; ++c) row += c == t.move(r, a) ? "1 " : "0 ";
        std::fprintf(out,
                     "<Entry><Instance>%s c%d c%d -</Instance><ProbTable>%s</ProbTable></Entry>\n",
                     kTagActions[a], r, o, row.c_str());
      }
    }
  }
  std::fprintf(out, "</Parameter></CondProb>\n");
  std::fprintf(out, "<CondProb><Var>opp_1</Var><Parent>action robot_0 opp_0</Parent><Parameter>\n");
  std::fprintf(out,
               "<Entry><Instance>* * tagged tagged</Instance><ProbTable>1</ProbTable></Entry>\n");
  for (int a = 0; a < 5; ++a) {
    for (int r = 0; r < n; ++r) {
      for (int o = 0; o < n; ++o) {
        std::vector<double> row(static_cast<std::size_t>(n) + 1, 0.0);
        if (a == 4 && r == o) {
          row.back() = 1.0;
        } else {
          for (const auto& [no, p] : t.flee(r, o)) row[static_cast<std::size_t>(no)] = p;
        }
        std::string text;
        for (double p : row) text += fmt::format("{} ", p);
        std::fprintf(out,
                     "<Entry><Instance>%s c%d c%d -</Instance><ProbTable>%s</ProbTable></Entry>\n",
                     kTagActions[a], r, o, text.c_str());
      }
    }
  }
  std::fprintf(out, "</Parameter></CondProb>\n</StateTransitionFunction>\n<ObsFunction>\n");
  std::fprintf(out, "<CondProb><Var>seen</Var><Parent>robot_1 opp_1</Parent><Parameter>\n");
  for (int r = 0; r < n; ++r) {
    for (int o = 0; o <= n; ++o) {
      std::fprintf(out, "<Entry><Instance>c%d %s %s</Instance><ProbTable>1</ProbTable></Entry>\n",
                   r, o == n ? "tagged" : fmt::format("c{}", o).c_str(),
                   o == n || o == r ? "seen" : fmt::format("at{}", r).c_str());
    }
  }
  std::fprintf(out, "</Parameter></CondProb>\n</ObsFunction>\n<RewardFunction>\n");
  std::fprintf(out, "<Func><Var>reward</Var><Parent>action robot_0 opp_0</Parent><Parameter>\n");
  std::fprintf(out, "<Entry><Instance>north * *</Instance><ValueTable>-1</ValueTable></Entry>\n");
  std::fprintf(out, "<Entry><Instance>south * *</Instance><ValueTable>-1</ValueTable></Entry>\n");
  std::fprintf(out, "<Entry><Instance>east * *</Instance><ValueTable>-1</ValueTable></Entry>\n");
  std::fprintf(out, "<Entry><Instance>west * *</Instance><ValueTable>-1</ValueTable></Entry>\n");
  std::fprintf(out, "<Entry><Instance>tag * *</Instance><ValueTable>-10</ValueTable></Entry>\n");
  for (int r = 0; r < n; ++r) {
    std::fprintf(
        out, "<Entry><Instance>tag c%d c%d</Instance><ValueTable>10</ValueTable></Entry>\n", r, r);
  }
  std::fprintf(out, "<Entry><Instance>* * tagged</Instance><ValueTable>0</ValueTable></Entry>\n");
  std::fprintf(out, "</Parameter></Func>\n</RewardFunction>\n</pomdpx>\n");
}

// Writes `problem` to `file` in the form its extension names.
template <typename Problem>
int write(const Problem& problem, void (*pomdp)(const Problem&, std::FILE*),
          void (*pomdpx)(const Problem&, std::FILE*), const std::string& file) {
  std::FILE* out = std::fopen(file.c_str(), "w");
  if (!out) return 1;
  (ends_with(file, ".pomdpx") ? pomdpx : pomdp)(problem, out);
  return std::fclose(out) == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes the standard POMDP benchmark problems too large to keep in the repository"};
  app.require_subcommand(1);
  const auto out_option = [](CLI::App* cmd, std::string& file) {
    cmd->add_option("out", file, "Output file: .pomdp (Cassandra) or .pomdpx")
        ->required()
        ->check([](const std::string& f) {
          return ends_with(f, ".pomdp") || ends_with(f, ".pomdpx")
                     ? std::string()
                     : std::string("must end in .pomdp or .pomdpx");
        });
  };
  RockSample rocksample;
  int k = 0;
  std::string rocksample_file, tag_file;
  auto* rocksample_cmd = app.add_subcommand(
      "rocksample", "RockSample(N, K), Smith and Simmons 2004; instances (4,4), (5,7), (7,8)");
  rocksample_cmd->add_option("n", rocksample.n, "Grid side")->required();
  rocksample_cmd->add_option("k", k, "Rocks")->required();
  rocksample_cmd
      ->add_option("half_efficiency_distance", rocksample.d0,
                   "Distance at which a check is right with probability 3/4")
      ->required()
      ->check(CLI::PositiveNumber);
  out_option(rocksample_cmd, rocksample_file);
  auto* tag_cmd = app.add_subcommand("tag", "Tag, Pineau et al. 2003");
  out_option(tag_cmd, tag_file);
  CLI11_PARSE(app, argc, argv);

  if (*tag_cmd) return write(Tag{}, write_tag_pomdp, write_tag_pomdpx, tag_file);
  const auto it = kRocks.find({rocksample.n, k});
  if (it == kRocks.end()) {
    std::fprintf(stderr, "gen_pomdp: no RockSample(%d,%d): instances (4,4), (5,7), (7,8)\n",
                 rocksample.n, k);
    return 2;
  }
  rocksample.rocks = it->second;
  return write(rocksample, write_rocksample_pomdp, write_rocksample_pomdpx, rocksample_file);
}
