// The library and chooser model shipped in configs/learned must match the
// code that reads them: the library's format and the action model it was
// made with, the model's features and the library it was trained on. When
// one does not, this fails naming the commands that remake them.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "plr/actions/fingerprint.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/sim/library.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path kLearned = fs::path(PLR_SOURCE_DIR) / "configs" / "learned";

const char* const kRemake =
    "; remake them from the repository's root: build/bin/plr run configs/learned/generate.yaml "
    "--report build/learned_generation, then rm -f configs/learned/data.plrd && build/bin/plr "
    "chooser train configs/learned/train_chooser.yaml";

TEST(Shipped, TheLibraryWasMadeWithThisActionModel) {
  const auto library = plr::sim::load_library(kLearned / "library.plrl");
  ASSERT_TRUE(library) << library.error().message << kRemake;
  EXPECT_GE(library->entries.size(), 2u) << kRemake;
  const auto now = plr::actions::action_model_fingerprint();
  ASSERT_TRUE(now) << now.error().message;
  EXPECT_EQ(library->action_model, *now)
      << "the shipped library was made with another action model" << kRemake;
  EXPECT_NE(library->made_by.find("configs/learned/generate.yaml"), std::string::npos)
      << library->made_by;
}

TEST(Shipped, TheModelReadsTheseFeaturesAndWasTrainedOnTheShippedLibrary) {
  const auto model = plr::chooser::Model::load(kLearned / "model.plrm");
  ASSERT_TRUE(model) << model.error().message << kRemake;
  const auto library = plr::sim::load_library(kLearned / "library.plrl");
  ASSERT_TRUE(library) << library.error().message << kRemake;
  EXPECT_EQ(model->library_crc(), plr::chooser::fingerprint(*library))
      << "the shipped model was trained on another library" << kRemake;
  EXPECT_EQ(model->made_by().rfind("plr chooser train: ", 0), 0u) << model->made_by();
}

}  // namespace
