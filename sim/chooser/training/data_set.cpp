#include "plr/chooser/training/data_set.hpp"

#include <plr/msg/chooser_data_generated.h>

#include <fmt/format.h>

#include <cmath>

#include "plr/sim/framed_file.hpp"

namespace plr::chooser {

namespace {

namespace msg = plr::msg;

plr::Error error(const std::string& where, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, where + ": " + what);
}

flatbuffers::Offset<msg::ChooserSample> build(flatbuffers::FlatBufferBuilder& fbb,
                                              const Sample& s) {
  return msg::CreateChooserSample(fbb, fbb.CreateString(s.world), s.step,
                                  fbb.CreateVector(s.features.data(), kFeatureCount), s.label,
                                  s.nearest, s.distance, s.nearest_boxes, s.nearest_seconds,
                                  s.hardcoded_boxes, s.hardcoded_seconds);
}

plr::Expected<std::vector<Sample>> read_samples(
    const flatbuffers::Vector<flatbuffers::Offset<msg::ChooserSample>>* v,
    const std::string& where) {
  std::vector<Sample> out;
  if (!v) return out;
  if (v->size() > kMaxSamples)
    return error(where, fmt::format("more than {} samples", kMaxSamples));
  for (flatbuffers::uoffset_t i = 0; i < v->size(); ++i) {
    const msg::ChooserSample* m = v->Get(i);
    const std::string at = fmt::format("{}[{}]", where, i);
    Sample s;
    s.world = m->world() ? m->world()->str().substr(0, 4096) : std::string();
    s.step = m->step();
    if (!m->features() || m->features()->size() != kFeatureCount)
      return error(at, fmt::format("features: {} values expected", kFeatureCount));
    for (std::size_t k = 0; k < kFeatureCount; ++k) {
      s.features[k] = m->features()->Get(static_cast<flatbuffers::uoffset_t>(k));
      if (!std::isfinite(s.features[k]))
        return error(at, fmt::format("features[{}]: not finite", k));
    }
    s.label = m->label();
    if (s.label != kNearestLabel && s.label != kHardcodedLabel)
      return error(at, fmt::format("label: {} is neither 1 nor -1", s.label));
    s.nearest = m->nearest();
    s.distance = m->distance();
    s.nearest_boxes = m->nearest_boxes();
    s.nearest_seconds = m->nearest_seconds();
    s.hardcoded_boxes = m->hardcoded_boxes();
    s.hardcoded_seconds = m->hardcoded_seconds();
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

plr::Status save_data_set(const DataSet& d, const std::filesystem::path& file) {
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<flatbuffers::Offset<msg::ChooserSample>> validation, training;
  for (const Sample& s : d.validation) validation.push_back(build(fbb, s));
  for (const Sample& s : d.training) training.push_back(build(fbb, s));
  std::vector<flatbuffers::Offset<msg::ChooserIteration>> iterations;
  for (const IterationRecord& r : d.iterations)
    iterations.push_back(msg::CreateChooserIteration(fbb, r.iteration, r.samples, r.cv_accuracy,
                                                     r.validation_accuracy, r.majority_accuracy,
                                                     r.c, r.gamma, r.wall_s));
  const auto mean = fbb.CreateVector(d.scaling.mean.data(), kFeatureCount);
  const auto scale = fbb.CreateVector(d.scaling.scale.data(), kFeatureCount);
  const auto v = fbb.CreateVector(validation);
  const auto t = fbb.CreateVector(training);
  const auto it = fbb.CreateVector(iterations);
  const auto state = fbb.CreateVector(d.state);
  msg::FinishChooserDataBuffer(
      fbb, msg::CreateChooserData(fbb, kDataSetVersion, kFeatureVersion, d.settings_hash, mean,
                                  scale, v, t, it, d.validating, d.world, d.step, state, d.wall_s));
  return sim::save_framed(plr::frame(fbb.GetBufferPointer(), fbb.GetSize()), file);
}

plr::Expected<DataSet> load_data_set(const std::filesystem::path& file) {
  auto bytes = sim::read_bounded_file(file, kMaxDataSetBytes + 8);
  if (!bytes) return bytes.error();
  return read_data_set(bytes->data(), bytes->size(), file.string());
}

plr::Expected<DataSet> read_data_set(const std::uint8_t* data, std::size_t size,
                                     const std::string& origin) {
  auto framed = sim::unframe(data, size, kMaxDataSetBytes, "a chooser data set", origin);
  if (!framed) return framed.error();
  if (!msg::ChooserDataBufferHasIdentifier(framed->data))
    return error(origin, "byte 8: not a chooser data set (identifier is not PLRD)");
  // A table per sample and iteration, beyond FlatBuffers' default of a million.
  flatbuffers::Verifier::Options options;
  options.max_tables = static_cast<flatbuffers::uoffset_t>(4 * kMaxSamples);
  flatbuffers::Verifier verifier(framed->data, framed->size, options);
  if (!msg::VerifyChooserDataBuffer(verifier))
    return error(
        origin, fmt::format("bytes 4..{}: malformed (FlatBuffers verification)", framed->size + 4));
  const msg::ChooserData* m = msg::GetChooserData(framed->data);
  if (m->version() != kDataSetVersion)
    return error(origin, fmt::format("version {} is not supported (this build reads {})",
                                     m->version(), kDataSetVersion));
  if (m->feature_version() != kFeatureVersion)
    return error(origin, fmt::format("features version {}; this build computes version {}: "
                                     "start the training anew in another folder",
                                     m->feature_version(), kFeatureVersion));
  DataSet d;
  d.settings_hash = m->settings_hash();
  if (!m->mean() || !m->scale() || m->mean()->size() != kFeatureCount ||
      m->scale()->size() != kFeatureCount)
    return error(origin, fmt::format("mean, scale: {} values each expected", kFeatureCount));
  for (std::size_t k = 0; k < kFeatureCount; ++k) {
    d.scaling.mean[k] = m->mean()->Get(static_cast<flatbuffers::uoffset_t>(k));
    d.scaling.scale[k] = m->scale()->Get(static_cast<flatbuffers::uoffset_t>(k));
    if (!std::isfinite(d.scaling.mean[k]) || !(d.scaling.scale[k] > 0) ||
        !std::isfinite(d.scaling.scale[k]))
      return error(origin, fmt::format("scale[{}]: must be finite and > 0", k));
  }
  auto validation = read_samples(m->validation(), origin + ": validation");
  if (!validation) return validation.error();
  d.validation = std::move(*validation);
  auto training = read_samples(m->training(), origin + ": training");
  if (!training) return training.error();
  d.training = std::move(*training);
  if (m->iterations()) {
    for (const msg::ChooserIteration* r : *m->iterations())
      d.iterations.push_back({r->iteration(), r->samples(), r->cv_accuracy(),
                              r->validation_accuracy(), r->majority_accuracy(), r->c(), r->gamma(),
                              r->wall_s()});
  }
  d.validating = m->validating();
  d.world = m->world();
  d.step = m->step();
  if (m->state()) d.state.assign(m->state()->begin(), m->state()->end());
  d.wall_s = m->wall_s();
  return d;
}

}  // namespace plr::chooser
