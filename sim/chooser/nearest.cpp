#include "plr/chooser/nearest.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <plr/frame.hpp>

namespace plr::chooser {

Features Scaling::apply(const Features& raw) const {
  Features out;
  for (std::size_t i = 0; i < kFeatureCount; ++i) out[i] = (raw[i] - mean[i]) / scale[i];
  return out;
}

Scaling Scaling::fit(const std::vector<Features>& samples) {
  Scaling s;
  for (std::size_t i = 0; i < kFeatureCount; ++i) s.scale[i] = resolution(i);
  if (samples.empty()) return s;
  const auto n = static_cast<double>(samples.size());
  for (const Features& f : samples)
    for (std::size_t i = 0; i < kFeatureCount; ++i) s.mean[i] += f[i] / n;
  for (std::size_t i = 0; i < kFeatureCount; ++i) {
    double var = 0;
    for (const Features& f : samples) var += (f[i] - s.mean[i]) * (f[i] - s.mean[i]) / n;
    s.scale[i] = std::max(std::sqrt(var), resolution(i));
  }
  return s;
}

LibraryIndex::LibraryIndex(const sim::Library& library, const Scaling& scaling,
                           const sim::ObservationParams& observation) {
  points_.reserve(library.entries.size());
  for (const sim::LibraryEntry& e : library.entries)
    points_.push_back(scaling.apply(features(e.world, observation)));
}

Nearest LibraryIndex::nearest(const Features& scaled) const {
  Nearest best{0, std::numeric_limits<double>::infinity()};
  for (std::size_t e = 0; e < points_.size(); ++e) {
    double d2 = 0;
    for (std::size_t i = 0; i < kFeatureCount; ++i)
      d2 += (scaled[i] - points_[e][i]) * (scaled[i] - points_[e][i]);
    // Ties go to the first entry, so the answer does not depend on rounding order.
    if (d2 < best.distance) best = {e, d2};
  }
  best.distance = std::sqrt(best.distance);
  return best;
}

std::uint32_t fingerprint(const sim::Library& library) {
  const std::vector<std::uint8_t> image = sim::serialize(library);
  return plr::crc32(image.data(), image.size());
}

}  // namespace plr::chooser
