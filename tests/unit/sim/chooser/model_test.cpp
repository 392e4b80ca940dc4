#include "plr/chooser/model.hpp"

#include <gtest/gtest.h>
#include <plr/msg/chooser_model_generated.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "plr/sim/framed_file.hpp"

using namespace plr::chooser;
namespace fs = std::filesystem;

namespace {

// Worlds described by two features that matter (the highest stack and the
// pile's depth) and noise in a few others: NN wins on high stacks over a
// short pile, H elsewhere.
struct Data {
  std::vector<Features> x;
  std::vector<int> y;
};
Data make_data(std::uint32_t seed, int n) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Data d;
  for (int i = 0; i < n; ++i) {
    Features f{};
    for (std::size_t k = 0; k < 5; ++k) f[k] = u(rng);
    f[kHighestStack] = 2.7 * u(rng);
    f[kPileDepth] = 2.0 * u(rng);
    d.x.push_back(f);
    d.y.push_back(f[kHighestStack] > 1.35 && f[kPileDepth] < 1.5 ? kNearestLabel : kHardcodedLabel);
  }
  return d;
}

fs::path temp(const std::string& name) {
  return fs::path(::testing::TempDir()) / ("plr_chooser_" + std::to_string(getpid()) + "_" + name);
}

Model trained() {
  const Data d = make_data(1, 120);
  return Model::train(d.x, d.y, Scaling::fit(d.x), 77).value();
}

TEST(Model, LearnsARuleAndCarriesItToUnseenWorlds) {
  const Model m = trained();
  const Data test = make_data(2, 200);
  int majority = 0;
  for (int y : test.y) majority += y == kHardcodedLabel;
  const double baseline = std::max(majority, 200 - majority) / 200.0;
  EXPECT_GT(m.accuracy(test.x, test.y), baseline + 0.1);
  EXPECT_GT(m.cv_accuracy(), 0.8);
  EXPECT_GT(m.support_vectors(), 0u);
  // The margin's sign is the verdict.
  for (const Features& f : test.x) {
    const Verdict v = m.decide(f);
    EXPECT_EQ(v.nearest, v.margin > 0);
  }
}

TEST(Model, TrainingIsDeterministic) {
  EXPECT_EQ(trained().serialize(), trained().serialize());
}

TEST(Model, WithOneClassAlwaysSaysIt) {
  const Data d = make_data(3, 10);
  const std::vector<int> all_h(d.x.size(), kHardcodedLabel);
  const Model m = Model::train(d.x, all_h, Scaling::fit(d.x), 0).value();
  EXPECT_FALSE(m.decide(d.x[0]).nearest);
  const Model back = Model::deserialize(m.serialize().data(), m.serialize().size(), "m").value();
  EXPECT_FALSE(back.decide(d.x[1]).nearest);
}

TEST(Model, ASavedModelLoadsWithTheSameVerdicts) {
  Model m = trained();
  m.set_made_by("plr chooser train: lib 77");
  const fs::path file = temp("round.plrm");
  ASSERT_TRUE(m.save(file));
  const Model back = Model::load(file).value();
  EXPECT_EQ(back.serialize(), m.serialize());
  EXPECT_EQ(back.library_crc(), 77u);
  EXPECT_EQ(back.made_by(), "plr chooser train: lib 77");
  for (const Features& f : make_data(4, 50).x) EXPECT_EQ(back.decide(f).margin, m.decide(f).margin);
  fs::remove(file);
}

TEST(Model, ACorruptFileIsRefusedWithWhereItIsCorrupt) {
  auto bytes = trained().serialize();
  bytes[bytes.size() / 2] ^= 0x40;
  const auto r = Model::deserialize(bytes.data(), bytes.size(), "m.plrm");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "m.plrm: bytes 4.." + std::to_string(bytes.size() - 4) +
                                   ": checksum mismatch (corrupt)");
}

TEST(Model, ATruncatedFileIsRefused) {
  const fs::path file = temp("cut.plrm");
  const auto bytes = trained().serialize();
  std::ofstream(file, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), 100);
  const auto r = Model::load(file);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message,
            file.string() + ": truncated: 100 of " + std::to_string(bytes.size()) + " bytes");
  fs::remove(file);
}

// A serialized model as its object, to alter (nullptr if it does not
// unframe). Through unframe: the body starts 4 bytes in, off the 8-byte
// boundary its doubles are read at.
plr::msg::ChooserModelT* unpacked(const std::vector<std::uint8_t>& bytes) {
  const auto body = plr::sim::unframe(bytes.data(), bytes.size(), bytes.size(), "a model", "test");
  return body ? plr::msg::GetChooserModel(body->data)->UnPack() : nullptr;
}

// A model written by a build whose features were version 0.
TEST(Model, AModelOfOtherFeaturesIsRefused) {
  auto bytes = trained().serialize();
  flatbuffers::FlatBufferBuilder fbb;
  auto obj = unpacked(bytes);
  ASSERT_NE(obj, nullptr);
  obj->feature_version = kFeatureVersion + 1;
  plr::msg::FinishChooserModelBuffer(fbb, plr::msg::ChooserModel::Pack(fbb, obj));
  delete obj;
  const auto framed = plr::frame(fbb.GetBufferPointer(), fbb.GetSize());
  const auto r = Model::deserialize(framed.data(), framed.size(), "old.plrm");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message,
            "old.plrm: trained on features version 2 (85 features); this build computes version "
            "1 (85): train the chooser again");
}

// Support counts are two int32 from the file; their sum must not overflow.
TEST(Model, SupportCountsWhoseSumOverflowsAnIntAreRefused) {
  auto bytes = trained().serialize();
  flatbuffers::FlatBufferBuilder fbb;
  auto obj = unpacked(bytes);
  ASSERT_NE(obj, nullptr);
  obj->labels = {kNearestLabel, kHardcodedLabel};
  obj->class_support = {INT32_MAX, INT32_MAX};
  plr::msg::FinishChooserModelBuffer(fbb, plr::msg::ChooserModel::Pack(fbb, obj));
  delete obj;
  const auto framed = plr::frame(fbb.GetBufferPointer(), fbb.GetSize());
  const auto r = Model::deserialize(framed.data(), framed.size(), "big.plrm");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message,
            "big.plrm: support_vectors: 4294967294 vectors of 85 values and as many coefficients "
            "expected");
}

TEST(Model, ALibraryIsNotAModel) {
  const auto bytes = trained().serialize();
  auto other = bytes;
  other[8] = 'X';  // the identifier, behind the size and the root offset
  const auto framed = plr::frame(other.data() + 4, other.size() - 8);
  const auto r = Model::deserialize(framed.data(), framed.size(), "lib.plrl");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "lib.plrl: byte 8: not a chooser model (identifier is not PLRM)");
}

}  // namespace
