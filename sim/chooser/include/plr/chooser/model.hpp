// The chooser's model M: an RBF-kernel SVM (libsvm) over scaled features
// that says whether the nearest library strategy (NN) or strategy H should
// run from a world; C and gamma chosen by k-fold cross-validation.
//
// File (extension .plrm): plr.msg.ChooserModel (sdk/schemas/chooser_model.fbs)
// in the frame of plr/sim/framed_file.hpp, written atomically. A file that is
// cut short, altered, malformed, of another layout or trained on other
// features (kFeatureVersion) is refused with one line naming the file.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "plr/chooser/features.hpp"
#include "plr/chooser/nearest.hpp"

namespace plr::chooser {

inline constexpr std::uint32_t kModelVersion = 1;
inline constexpr std::size_t kMaxModelBytes = std::size_t{1} << 28;

// Labels: which strategy unloaded faster from a state.
inline constexpr int kNearestLabel = 1;
inline constexpr int kHardcodedLabel = -1;
// In made_by() when the training's data set was below its min_samples.
inline constexpr std::string_view kBelowMinimum = "below the minimum of";

struct TrainOptions {
  int folds = 5;
  // log2 of the grid: C = 2^c, gamma = 2^g (LIBSVM's guide's coarse grid).
  std::vector<int> log2_c{-1, 1, 3, 5, 7, 9};
  std::vector<int> log2_gamma{-11, -9, -7, -5, -3, -1};
};

struct Verdict {
  bool nearest = false;  // run NN's strategy; else H
  double margin = 0.0;   // the SVM's decision value towards NN (> 0: NN)
};

class Model {
 public:
  Model(Model&&) noexcept;
  Model& operator=(Model&&) noexcept;
  ~Model();

  // Trains on `raw` features (scaled here with `scaling`) and their labels
  // (kNearestLabel or kHardcodedLabel): the grid point with the best
  // cross-validated accuracy (the first on ties), then all samples. With one
  // class only, the model always says that class.
  static plr::Expected<Model> train(const std::vector<Features>& raw,
                                    const std::vector<int>& labels, const Scaling& scaling,
                                    std::uint32_t library_crc, const TrainOptions& options = {});

  // For features not yet scaled.
  Verdict decide(const Features& raw) const;
  // Fraction of samples whose label the model gives.
  double accuracy(const std::vector<Features>& raw, const std::vector<int>& labels) const;

  const Scaling& scaling() const;
  std::uint32_t library_crc() const;
  double c() const;
  double gamma() const;
  double cv_accuracy() const;
  std::size_t support_vectors() const;
  // The command and settings that made it (recorded in the file).
  // How it was made (the training's settings); holds kBelowMinimum when its
  // data set was smaller than the training's min_samples.
  const std::string& made_by() const;
  void set_made_by(std::string made_by);

  std::vector<std::uint8_t> serialize() const;
  static plr::Expected<Model> deserialize(const std::uint8_t* data, std::size_t size,
                                          const std::string& origin);
  plr::Status save(const std::filesystem::path& file) const;
  static plr::Expected<Model> load(const std::filesystem::path& file);

 private:
  struct Impl;
  explicit Model(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace plr::chooser
