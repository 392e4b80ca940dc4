// The chooser's training data set D and the state of its training: labelled
// states (validation and training), the accuracy after each iteration, and
// the state the next label starts from. Saved after every labelled state
// (atomically, sdk/schemas/chooser_data.fbs in the frame of
// plr/sim/framed_file.hpp), so a killed training resumes where it stood.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "plr/chooser/features.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"

namespace plr::chooser {

inline constexpr std::uint32_t kDataSetVersion = 1;
inline constexpr std::size_t kMaxDataSetBytes = std::size_t{1} << 30;
inline constexpr std::size_t kMaxSamples = 1000000;

struct Sample {
  std::string world;
  std::uint32_t step = 0;
  Features features{};
  int label = 0;
  std::uint32_t nearest = 0;
  double distance = 0.0;
  std::uint32_t nearest_boxes = 0;
  double nearest_seconds = 0.0;
  std::uint32_t hardcoded_boxes = 0;
  double hardcoded_seconds = 0.0;
};

struct IterationRecord {
  std::uint32_t iteration = 0;
  std::uint32_t samples = 0;
  double cv_accuracy = 0.0;
  double validation_accuracy = 0.0;
  double majority_accuracy = 0.0;
  double c = 0.0, gamma = 0.0;
  double wall_s = 0.0;
};

struct DataSet {
  std::uint64_t settings_hash = 0;
  Scaling scaling;
  std::vector<Sample> validation, training;
  std::vector<IterationRecord> iterations;
  bool validating = true;
  std::uint32_t world = 0, step = 0;
  std::vector<std::uint8_t> state;  // TruckState; empty: the world's start
  double wall_s = 0.0;
};

plr::Status save_data_set(const DataSet& data, const std::filesystem::path& file);
// Errors are one line naming the file and what is wrong with it.
plr::Expected<DataSet> load_data_set(const std::filesystem::path& file);
// The same from a file's bytes; `origin` names them in errors.
plr::Expected<DataSet> read_data_set(const std::uint8_t* data, std::size_t size,
                                     const std::string& origin);

}  // namespace plr::chooser
