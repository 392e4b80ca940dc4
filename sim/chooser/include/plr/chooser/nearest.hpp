// The chooser's nearest neighbour NN: the library entry whose generating
// world lies nearest, in scaled feature space, to the world in front of the
// robot. Scaling is a z-score per feature, fitted once on training worlds and
// stored with the model, so that NN and the SVM measure the same space.
#pragma once

#include <cstddef>
#include <vector>

#include "plr/chooser/features.hpp"
#include "plr/sim/library.hpp"

namespace plr::chooser {

struct Scaling {
  Features mean{};
  // The standard deviation, at least the feature's resolution(): fitted on
  // a few starting worlds, a feature that hardly varies among them (how far
  // the load has been worked) would otherwise turn any later change into
  // dozens of deviations and swamp the distance.
  Features scale{};

  Features apply(const Features& raw) const;
  static Scaling fit(const std::vector<Features>& samples);
};

struct Nearest {
  std::size_t entry = 0;  // index into the library's entries
  double distance = 0.0;  // Euclidean, in scaled features
};

// The library's generating worlds in scaled features. Brute force: a
// library holds a handful to hundreds of entries (85 doubles each).
class LibraryIndex {
 public:
  LibraryIndex(const sim::Library& library, const Scaling& scaling,
               const sim::ObservationParams& observation = {});

  // The library must not be empty.
  Nearest nearest(const Features& scaled) const;
  std::size_t size() const { return points_.size(); }

 private:
  std::vector<Features> points_;
};

// CRC-32 of the library's file image: a model names the library NN searched
// when it was trained.
std::uint32_t fingerprint(const sim::Library& library);

}  // namespace plr::chooser
