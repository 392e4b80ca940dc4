#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "plr/sim/generators.hpp"

namespace plr::sim {
namespace {

const std::vector<EnvFamily> kFamilies = all_env_families();

double mean_mass(const World& w) {
  double s = 0.0;
  for (const Box& b : w.boxes) s += b.mass;
  return s / static_cast<double>(w.boxes.size());
}

TEST(Generators, A1HasAtLeast150Boxes) {
  for (std::uint64_t seed = 0; seed < 30; ++seed) {
    EXPECT_GE(generate_world(EnvFamily::kA1, seed).boxes.size(), 150u) << seed;
  }
}

TEST(Generators, SameSeedSameWorldOtherSeedOtherWorld) {
  for (EnvFamily f : kFamilies) {
    const World a = generate_world(f, 9), b = generate_world(f, 9), c = generate_world(f, 10);
    ASSERT_EQ(a.boxes.size(), b.boxes.size());
    for (std::size_t i = 0; i < a.boxes.size(); ++i) {
      EXPECT_EQ(a.boxes[i].pose.matrix(), b.boxes[i].pose.matrix());
      EXPECT_EQ(a.boxes[i].mass, b.boxes[i].mass);
    }
    EXPECT_NE(mean_mass(a), mean_mass(c)) << to_string(f);
  }
}

TEST(Generators, BoxesFillFromTheFrontAndLeaveTheRearFree) {
  for (EnvFamily f : kFamilies) {
    for (std::uint64_t seed = 0; seed < 10; ++seed) {
      const World w = generate_world(f, seed);
      double max_x = 0.0, min_x = 1e9;
      for (const Box& b : w.boxes) {
        max_x = std::max(max_x, b.pose.translation().x());
        min_x = std::min(min_x, b.pose.translation().x());
        EXPECT_GT(b.mass, 0.0);
      }
      EXPECT_GT(max_x, w.trailer.depth - 0.5) << to_string(f);
      EXPECT_GT(min_x, 0.5 * w.trailer.depth) << to_string(f);
    }
  }
}

TEST(Generators, NoInterpenetration) {
  for (EnvFamily f : kFamilies) {
    for (std::uint64_t seed = 0; seed < 20; ++seed) {
      EXPECT_TRUE(find_interpenetrations(generate_world(f, seed), 1e-6).empty())
          << to_string(f) << " seed " << seed;
    }
  }
}

TEST(Generators, FamiliesDifferInSizesAndMasses) {
  double a1 = 0, a2 = 0, sizes1 = 0, sizes2 = 0;
  for (std::uint64_t seed = 0; seed < 10; ++seed) {
    const World w1 = generate_world(EnvFamily::kA1, seed),
                w2 = generate_world(EnvFamily::kA2, seed);
    a1 += mean_mass(w1);
    a2 += mean_mass(w2);
    sizes1 += static_cast<double>(w1.boxes.size());
    sizes2 += static_cast<double>(w2.boxes.size());
  }
  EXPECT_GT(a2, 1.2 * a1);          // A2 is heavier
  EXPECT_LT(sizes2, 0.9 * sizes1);  // with fewer, larger boxes
}

Box upright(std::uint32_t id, const Eigen::Vector3d& size, const Eigen::Vector3d& centre,
            double mass) {
  Box b;
  b.id = id;
  b.size = size;
  b.pose = Eigen::Isometry3d::Identity();
  b.pose.translation() = centre;
  b.mass = mass;
  return b;
}

// Each box of a leaning column rests on the one below with its centre over
// that box's top, but the top two together lean out too far over the middle
// one: the middle one (and what it carries) tips.
TEST(Generators, StaticsFindsAColumnLeaningOverAsAWhole) {
  World w;
  const Eigen::Vector3d size(0.4, 0.4, 0.3);
  w.boxes.push_back(upright(1, size, {10.0, 0.0, 0.15}, 5.0));
  w.boxes.push_back(upright(2, size, {10.1, 0.0, 0.45}, 5.0));
  EXPECT_TRUE(toppling_boxes(w).empty());
  w.boxes.push_back(upright(3, size, {10.2, 0.0, 0.75}, 5.0));
  EXPECT_EQ(toppling_boxes(w), std::vector<std::uint32_t>{2});
  // A heavy box on top of the light leaning one makes it worse, a light one
  // matters less: loads count, not box counts.
  w.boxes[2].pose.translation().x() = 10.14;
  w.boxes[2].mass = 1.0;
  EXPECT_TRUE(toppling_boxes(w).empty());
  w.boxes[2].mass = 30.0;
  EXPECT_EQ(toppling_boxes(w), std::vector<std::uint32_t>{2});
}

// A box bridging two supports stands, its load shared by the lever rule;
// off-centre loads on a bridge move its load towards one support.
TEST(Generators, StaticsSharesABridgedLoad) {
  World w;
  w.boxes.push_back(upright(1, {0.3, 0.3, 0.3}, {10.0, 0.0, 0.15}, 5.0));
  w.boxes.push_back(upright(2, {0.3, 0.3, 0.3}, {10.4, 0.0, 0.15}, 5.0));
  w.boxes.push_back(upright(3, {0.6, 0.3, 0.2}, {10.2, 0.0, 0.4}, 20.0));
  EXPECT_TRUE(toppling_boxes(w).empty());
  // Shifted so that it hangs mostly over box 2: box 1 holds little and box
  // 2's load passes near its outer edge, but both still stand.
  w.boxes[2].pose.translation().x() = 10.3;
  EXPECT_TRUE(toppling_boxes(w).empty());
}

TEST(Generators, PilesStand) {
  for (EnvFamily f : {EnvFamily::kB1, EnvFamily::kB2}) {
    for (std::uint64_t seed = 0; seed < 20; ++seed) {
      EXPECT_TRUE(toppling_boxes(generate_world(f, seed)).empty())
          << to_string(f) << " seed " << seed;
    }
  }
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Particles draw masses from the distribution the generators draw from:
// same median and clipping, and (like the generators) unrelated to size.
TEST(MassPrior, SampledMassesFollowTheGenerators) {
  for (EnvFamily f : kFamilies) {
    const MassPrior prior = mass_prior(f);
    std::vector<double> generated, sampled, volume;
    for (std::uint64_t seed = 0; seed < 10; ++seed) {
      const World w = generate_world(f, seed);
      for (const Box& b : w.boxes) {
        generated.push_back(b.mass);
        volume.push_back(b.size.prod());
      }
      for (const Box& b : sample_masses(without_masses(w), f, seed).boxes)
        sampled.push_back(b.mass);
    }
    for (const double m : sampled) {
      ASSERT_GE(m, prior.min);
      ASSERT_LE(m, prior.max);
    }
    EXPECT_NEAR(median_of(generated), prior.median, 0.1 * prior.median) << to_string(f);
    EXPECT_NEAR(median_of(sampled), prior.median, 0.1 * prior.median) << to_string(f);
    const auto clipped = [&](const std::vector<double>& v) {
      const auto n = std::count_if(v.begin(), v.end(),
                                   [&](double m) { return m == prior.min || m == prior.max; });
      return static_cast<double>(n) / static_cast<double>(v.size());
    };
    EXPECT_NEAR(clipped(sampled), clipped(generated), 0.03) << to_string(f);
    // Size and mass are independent in the generators (else the prior would
    // have to be conditioned on the box's volume).
    const double n = static_cast<double>(generated.size());
    const double mm = std::accumulate(generated.begin(), generated.end(), 0.0) / n;
    const double mv = std::accumulate(volume.begin(), volume.end(), 0.0) / n;
    double cov = 0, vm = 0, vv = 0;
    for (std::size_t i = 0; i < generated.size(); ++i) {
      cov += (generated[i] - mm) * (volume[i] - mv);
      vm += (generated[i] - mm) * (generated[i] - mm);
      vv += (volume[i] - mv) * (volume[i] - mv);
    }
    // (D's cartons are all of one size: nothing to correlate.)
    if (vv > 0) {
      EXPECT_LT(std::abs(cov / std::sqrt(vm * vv)), 0.1) << to_string(f);
    }
  }
}

TEST(MassPrior, SamplesDependOnSeedAndBoxOnly) {
  const World visible = without_masses(generate_world(EnvFamily::kB1, 4));
  const World a = sample_masses(visible, EnvFamily::kB1, 7);
  const World b = sample_masses(visible, EnvFamily::kB1, 7);
  const World c = sample_masses(visible, EnvFamily::kB1, 8);
  ASSERT_EQ(a.boxes.size(), visible.boxes.size());
  int differ = 0;
  for (std::size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_EQ(a.boxes[i].mass, b.boxes[i].mass);
    differ += a.boxes[i].mass != c.boxes[i].mass;
  }
  EXPECT_GT(differ, static_cast<int>(a.boxes.size()) / 2);
  // A box leaving the world does not change the others' masses; known
  // masses stay as they are.
  World fewer = visible;
  fewer.boxes.erase(fewer.boxes.begin());
  fewer.boxes[0].mass = 12.5;
  const World d = sample_masses(fewer, EnvFamily::kB1, 7);
  EXPECT_EQ(d.boxes[0].mass, 12.5);
  for (std::size_t i = 1; i < d.boxes.size(); ++i) EXPECT_EQ(d.boxes[i].mass, a.boxes[i + 1].mass);
}

TEST(MassPrior, SetMassesByIdOrNotAtAll) {
  World w = without_masses(generate_world(EnvFamily::kA1, 2));
  ASSERT_TRUE(set_masses(w, {{w.boxes[3].id, 4.5}, {w.boxes[0].id, 20.0}}).has_value());
  EXPECT_EQ(w.boxes[3].mass, 4.5);
  EXPECT_EQ(w.boxes[0].mass, 20.0);
  const plr::Status missing = set_masses(w, {{w.boxes[1].id, 3.0}, {99999, 3.0}});
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().message, "set_masses: no box 99999");
  EXPECT_EQ(w.boxes[1].mass, 0.0);  // nothing changed
  const plr::Status nan = set_masses(w, {{w.boxes[1].id, std::nan("")}});
  ASSERT_FALSE(nan.has_value());
  EXPECT_EQ(nan.error().message,
            "set_masses: box " + std::to_string(w.boxes[1].id) + ": mass must be finite and > 0");
}

// C: walls with something changed in front, in trailers and containers.
TEST(Generators, CMixesWallsFloorBoxesAndContainers) {
  int containers = 0, with_floor_boxes = 0;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const World w = generate_world(EnvFamily::kC, seed);
    ASSERT_FALSE(w.boxes.empty());
    containers += w.trailer.width == 2.35 ? 1 : 0;
    // Fallen and loose boxes lie flat on the floor, turned.
    int floor = 0;
    for (const Box& b : w.boxes) {
      EXPECT_GT(b.pose.translation().x(), 0.5 * w.trailer.depth);
      const bool flat = std::abs(b.pose.linear()(2, 2) - 1.0) < 1e-9;
      floor += flat && b.pose.translation().z() < 0.35 && b.size.z() <= b.size.x() &&
               b.size.z() <= b.size.y() && b.pose.linear()(0, 0) < 0.999;
    }
    with_floor_boxes += floor > 0 ? 1 : 0;
    // Ids are 1..n.
    for (std::size_t i = 0; i < w.boxes.size(); ++i) EXPECT_EQ(w.boxes[i].id, i + 1);
  }
  EXPECT_GE(containers, 5);
  EXPECT_LE(containers, 18);
  EXPECT_GE(with_floor_boxes, 5);
}

// D: cartons stacked to just under the ceiling, light, heavy, loose on top.
double top_of(const Box& b) {
  return b.pose.translation().z() + (b.pose.linear().cwiseAbs() * (0.5 * b.size)).z();
}

TEST(Generators, DWallsReachTheCeiling) {
  for (EnvFamily f : {EnvFamily::kD1, EnvFamily::kD2, EnvFamily::kD3}) {
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      const World w = generate_world(f, seed);
      double top = 0;
      for (const Box& b : w.boxes) {
        top = std::max(top, top_of(b));
        EXPECT_NEAR(b.size.x(), 0.5, 1e-12);
        EXPECT_NEAR(b.size.z(), 0.53, 1e-12);  // five layers to 2.65 m
      }
      EXPECT_NEAR(top, 2.65, 1e-9) << to_string(f);
      EXPECT_TRUE(toppling_boxes(w).empty()) << to_string(f) << " seed " << seed;
      for (std::size_t i = 0; i < w.boxes.size(); ++i) EXPECT_EQ(w.boxes[i].id, i + 1);
      // Four columns of five, three slabs deep; the loose layers (24 places)
      // leave gaps where a turned carton would overlap its neighbours.
      if (f == EnvFamily::kD3) {
        EXPECT_GE(w.boxes.size(), 36u + 8u);
        EXPECT_LT(w.boxes.size(), 60u);
      } else {
        EXPECT_EQ(w.boxes.size(), 60u);
      }
    }
  }
}

TEST(Generators, DVariantsDifferInMassAndLayout) {
  double d1 = 0, d2 = 0;
  int turned = 0, turned_low = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    d1 += mean_mass(generate_world(EnvFamily::kD1, seed));
    d2 += mean_mass(generate_world(EnvFamily::kD2, seed));
    for (const Box& b : generate_world(EnvFamily::kD3, seed).boxes) {
      const bool t = b.pose.linear()(0, 0) < 0.999;
      turned += t;
      turned_low += t && b.pose.translation().z() < 3 * 0.53;
    }
  }
  EXPECT_GT(d2, 4 * d1);     // heavy cartons
  EXPECT_GT(turned, 100);    // the two loose layers, out of line
  EXPECT_EQ(turned_low, 0);  // the three below stand in columns
}

TEST(Generators, CartonWallOfAnyShape) {
  CartonWall small;
  small.columns = 2;
  small.slabs = 1;
  const auto w = make_carton_wall(small, 4);
  ASSERT_TRUE(w.has_value()) << w.error().message;
  ASSERT_EQ(w->boxes.size(), 10u);
  double y_min = 9, y_max = -9;
  for (const Box& b : w->boxes) {
    y_min = std::min(y_min, b.pose.translation().y());
    y_max = std::max(y_max, b.pose.translation().y());
  }
  EXPECT_NEAR(y_min + y_max, 0.0, 0.01);  // centred
  EXPECT_NEAR(y_max - y_min, 0.51, 0.01);
  // A lower trailer: fewer, taller layers, still up to the headroom.
  const auto low = make_carton_wall(small, 4, Trailer{2.35, 2.39, 12.0});
  ASSERT_TRUE(low.has_value());
  double top = 0;
  for (const Box& b : low->boxes) top = std::max(top, top_of(b));
  EXPECT_NEAR(top, 2.34, 1e-9);
  EXPECT_EQ(low->boxes.size(), 8u);
}

TEST(Generators, CartonWallRefusesWhatDoesNotFit) {
  const auto error = [](CartonWall w, Trailer t = {}) {
    const auto r = make_carton_wall(w, 1, t);
    return r ? std::string() : r.error().message;
  };
  CartonWall w;
  w.columns = 5;
  EXPECT_EQ(error(w), "carton wall: columns 5: a 2.5 m trailer holds 1-4 columns of 0.5 m cartons");
  w = {};
  w.headroom = 2.5;
  EXPECT_EQ(error(w),
            "carton wall: headroom 2.5 m: must be >= 0 and leave a 0.5 m carton under the 2.7 m "
            "ceiling");
  w = {};
  w.slabs = 20;
  EXPECT_EQ(
      error(w),
      "carton wall: slabs 20: must be >= 1 and fill at most the front half of a 16 m trailer");
  w = {};
  w.loose_layers = 6;
  EXPECT_EQ(error(w), "carton wall: loose_layers 6: must be within 0-5 (the wall's layers)");
  w = {};
  w.mass.min = 0;
  EXPECT_EQ(error(w), "carton wall: mass: needs 0 < min <= median <= max and spread >= 0");
  w = {};
  w.carton = 0;
  EXPECT_EQ(error(w), "carton wall: carton 0 m: must be within 0.1-1.5 m");
}

TEST(Generators, FamilyNames) {
  EXPECT_EQ(parse_env_family("d2"), EnvFamily::kD2);
  EXPECT_EQ(parse_env_family("b2"), EnvFamily::kB2);
  EXPECT_EQ(parse_env_family("c"), EnvFamily::kC);
  EXPECT_EQ(parse_env_family("A1"), EnvFamily::kA1);
  EXPECT_FALSE(parse_env_family("C1").has_value());
  EXPECT_FALSE(parse_env_family("A").has_value());
}

}  // namespace
}  // namespace plr::sim
