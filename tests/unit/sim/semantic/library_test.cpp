#include "plr/sim/library.hpp"

#include <gtest/gtest.h>

#include <plr/msg/library_generated.h>

#include "plr/sim/framed_file.hpp"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace plr::sim;

namespace {

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "plr_library_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

LibraryEntry entry(const std::string& name) {
  LibraryEntry e;
  e.name = name;
  e.family = "A1";
  e.world_seed = 3;
  e.world.trailer.depth = 12.0;
  Box b;
  b.id = 7;
  b.size = {0.4, 0.5, 0.3};
  b.pose.translation() = Eigen::Vector3d(11.5, 0.2, 0.15);
  e.world.boxes.push_back(b);
  e.observation_json = R"({"h_pile":0.55})";
  e.strategy.name = name;
  e.strategy.nodes = {{make_pick(Height::kHigh, Side::kLeft),
                       {{make_observation(Structure::kWall, Height::kMid, Side::kCenter), 1}}},
                      {make_sweep(Height::kLow), {}}};
  e.lower = -120.5;
  e.upper = -40.25;
  e.provenance.seed = 9;
  e.provenance.particles = 5;
  e.provenance.horizon = 6;
  e.provenance.trials = 60;
  e.provenance.created = "2026-11-26T19:00:00Z";
  e.curve = {{1.0, -300, -0.5, 1}, {2.0, -200, -10, 2}};
  return e;
}

std::vector<std::uint8_t> read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

TEST(Library, RoundTripsThroughItsFile) {
  TempDir dir;
  Library lib;
  lib.entries = {entry("A1-3"), entry("B1-1")};
  lib.made_by = "plr run configs/generate.yaml\nsettings: {}";
  lib.action_model = "v2-0123abcd";
  ASSERT_TRUE(save_library(lib, dir / "l.plrl"));
  const auto back = load_library(dir / "l.plrl");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->made_by, lib.made_by);
  EXPECT_EQ(back->action_model, lib.action_model);
  ASSERT_EQ(back->entries.size(), 2u);
  const LibraryEntry& e = back->entries[1];
  EXPECT_EQ(e.name, "B1-1");
  EXPECT_EQ(e.world_seed, 3u);
  ASSERT_EQ(e.world.boxes.size(), 1u);
  EXPECT_EQ(e.world.boxes[0].id, 7u);
  EXPECT_DOUBLE_EQ(e.world.boxes[0].pose.translation().y(), 0.2);
  EXPECT_EQ(e.world.boxes[0].mass, 0.0);
  EXPECT_EQ(format_yaml(e.strategy), format_yaml(entry("B1-1").strategy));
  EXPECT_DOUBLE_EQ(e.lower, -120.5);
  EXPECT_DOUBLE_EQ(e.upper, -40.25);
  EXPECT_EQ(e.provenance.particles, 5u);
  EXPECT_EQ(e.provenance.created, "2026-11-26T19:00:00Z");
  ASSERT_EQ(e.curve.size(), 2u);
  EXPECT_EQ(e.curve[1].trials, 2u);
  EXPECT_EQ(serialize(*back), serialize(lib));
}

TEST(Library, AContinuationKeepsItsParentItsLeafAndTheBeliefItStartsFrom) {
  TempDir dir;
  Library lib;
  lib.entries = {entry("A1-3"), entry("A1-3.1")};
  LibraryEntry& c = lib.entries[1];
  c.parent = "A1-3";
  c.leaf = {make_observation(Structure::kWall, Height::kMid, Side::kCenter),
            make_observation(Structure::kPile, Height::kLow, Side::kRight)};
  c.start = {{0, 0x0123456789abcdefull, 40}, {3, 0xfedcba9876543210ull, 38}};
  ASSERT_TRUE(save_library(lib, dir / "l.plrl"));
  const auto back = load_library(dir / "l.plrl");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_FALSE(back->entries[0].is_continuation());
  EXPECT_TRUE(back->entries[0].leaf.empty());
  EXPECT_TRUE(back->entries[0].start.empty());
  const LibraryEntry& e = back->entries[1];
  EXPECT_EQ(e.parent, "A1-3");
  EXPECT_EQ(e.leaf, c.leaf);
  EXPECT_EQ(e.start, c.start);
  EXPECT_EQ(continuations(*back, 0), std::vector<std::size_t>{1});
  EXPECT_TRUE(continuations(*back, 1).empty());
  EXPECT_EQ(serialize(*back), serialize(lib));

  // A continuation without the belief it starts from says so.
  lib.entries[1].start.clear();
  ASSERT_TRUE(save_library(lib, dir / "l.plrl"));
  const auto refused = load_library(dir / "l.plrl");
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("entries[1] 'A1-3.1': a continuation"), std::string::npos)
      << refused.error().message;
}

// A library written before worlds were kept exactly (and before entries
// could be continuations: the shipped library of 2026-12-07, copied) still
// reads, its rotations from the quaternions; a strategy for a fresh trailer
// is written without the continuation's fields, as then.
TEST(Library, AFileMadeBeforeExactWorldsReadsFromItsQuaternions) {
  const fs::path old = fs::path(PLR_SOURCE_DIR) / "tests/unit/sim/semantic/data" /
                       "library_before_exact_worlds.plrl";
  const std::vector<std::uint8_t> bytes = read(old);
  const auto* file = plr::msg::GetStrategyLibrary(bytes.data() + 4);
  for (const auto* e : *file->entries()) EXPECT_EQ(e->world_rotations(), nullptr);
  const auto lib = load_library(old);
  ASSERT_TRUE(lib) << lib.error().message;
  ASSERT_FALSE(lib->entries.empty());
  for (const LibraryEntry& e : lib->entries) {
    EXPECT_FALSE(e.is_continuation()) << e.name;
    EXPECT_EQ(e.fidelity, "full");
    EXPECT_FALSE(e.check);
    for (const Box& b : e.world.boxes)
      EXPECT_TRUE((b.pose.linear().transpose() * b.pose.linear()).isIdentity(1e-12)) << e.name;
  }
  const std::vector<std::uint8_t> image = serialize(*lib);
  const auto* m = plr::msg::GetStrategyLibrary(image.data() + 4);
  for (const auto* e : *m->entries()) {
    EXPECT_EQ(e->parent(), nullptr);
    EXPECT_EQ(e->leaf(), nullptr);
    EXPECT_EQ(e->start(), nullptr);
    EXPECT_EQ(e->fidelity(), nullptr);
    EXPECT_EQ(e->check(), nullptr);
    ASSERT_NE(e->world_rotations(), nullptr);
  }
  // Written again, it is in this format: read back, the same bytes.
  const auto again = deserialize_library(image.data(), image.size(), "image");
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_EQ(serialize(*again), image);
}

// The shipped library must be in the format this code writes: the chooser
// model's CRC of it is of the bytes serialize() gives (Shipped.* in
// tests/unit/sim/chooser). It fails when the format changed and the shipped
// files were not made again.
TEST(Library, TheShippedLibraryIsWrittenBackAsItIs) {
  const fs::path shipped = fs::path(PLR_SOURCE_DIR) / "configs/learned/library.plrl";
  const auto lib = load_library(shipped);
  ASSERT_TRUE(lib) << lib.error().message;
  EXPECT_TRUE(serialize(*lib) == read(shipped))
      << "configs/learned/library.plrl is not in this build's format; remake it and the chooser "
         "model from the repository's root: build/bin/plr run configs/learned/generate.yaml "
         "--report build/learned_generation, then rm -f configs/learned/data.plrd && "
         "build/bin/plr chooser train configs/learned/train_chooser.yaml";
}

// A world goes through the file bit for bit: positions and sizes are
// doubles in the file, and each rotation is stored as its matrix beside the
// quaternion (which alone gives it back only to the last bits: a pile's
// simulation turns on them, docs/generator.md).
TEST(Library, AWorldWithRotatedBoxesComesBackBitForBit) {
  LibraryEntry e = entry("A1-1");
  e.world.trailer = {2.4871, 2.6993, 15.8127};
  e.world.boxes.clear();
  std::uint32_t lost = 0;  // boxes whose quaternion alone would not give their rotation back
  for (std::uint32_t i = 0; i < 40; ++i) {
    Box b;
    b.id = 100 + i;
    b.size = {0.3 + 0.0137 * i, 0.41 + 0.0071 * i, 0.27 + 0.0093 * i};
    const Eigen::Vector3d axis = Eigen::Vector3d(0.3 + 0.1 * i, -0.7, 1.1 - 0.05 * i).normalized();
    b.pose = Eigen::Translation3d(0.5 + 0.31 * i, -0.9 + 0.043 * i, 0.2 + 0.017 * i) *
             Eigen::AngleAxisd(0.013 + 0.157 * i, axis);
    const Eigen::Matrix3d via_quaternion = Eigen::Quaterniond(b.pose.linear()).toRotationMatrix();
    lost += std::memcmp(via_quaternion.data(), b.pose.linear().data(), 9 * sizeof(double)) != 0;
    e.world.boxes.push_back(b);
  }
  ASSERT_GT(lost, 0u) << "no rotation here would lose bits through a quaternion: the test could "
                         "not fail";
  Library lib;
  lib.entries = {e};
  const std::vector<std::uint8_t> bytes = serialize(lib);
  const auto back = deserialize_library(bytes.data(), bytes.size(), "l.plrl");
  ASSERT_TRUE(back) << back.error().message;
  const World& w = back->entries.at(0).world;
  EXPECT_EQ(std::memcmp(&w.trailer, &e.world.trailer, sizeof(Trailer)), 0);
  ASSERT_EQ(w.boxes.size(), e.world.boxes.size());
  for (std::size_t i = 0; i < w.boxes.size(); ++i) {
    const Box &a = w.boxes[i], &b = e.world.boxes[i];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(std::memcmp(a.size.data(), b.size.data(), 3 * sizeof(double)), 0) << i;
    EXPECT_EQ(std::memcmp(a.pose.matrix().data(), b.pose.matrix().data(), 16 * sizeof(double)), 0)
        << "box " << i;
    EXPECT_EQ(a.mass, 0.0);
  }
  // And the bytes: read and written again, the same.
  EXPECT_EQ(serialize(*back), bytes);
}

TEST(Library, AStrategyMadeBelowFullFidelityKeepsItsLevelAndBothValues) {
  Library lib;
  lib.entries = {entry("A1-1"), entry("B1-1")};
  LibraryEntry& fast = lib.entries[1];
  fast.fidelity = "fast";
  fast.check = FidelityCheck{-310.5, 12.25, -402.75, 9.5, 5, 1000};
  const std::vector<std::uint8_t> bytes = serialize(lib);
  const auto back = deserialize_library(bytes.data(), bytes.size(), "l.plrl");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->entries[0].fidelity, "full");
  EXPECT_FALSE(back->entries[0].check);
  EXPECT_EQ(back->entries[1].fidelity, "fast");
  ASSERT_TRUE(back->entries[1].check);
  EXPECT_EQ(*back->entries[1].check, *fast.check);
  EXPECT_EQ(serialize(*back), bytes);

  fast.fidelity = "quick";
  const std::vector<std::uint8_t> bad = serialize(lib);
  const auto refused = deserialize_library(bad.data(), bad.size(), "l.plrl");
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.error().message,
            "l.plrl: entries[1] 'B1-1': fidelity: 'quick' is not full, adaptive or fast");
}

TEST(Library, TruncatedFileIsRefusedWithWhereItEnds) {
  TempDir dir;
  Library lib;
  lib.entries = {entry("A1-3")};
  ASSERT_TRUE(save_library(lib, dir / "l.plrl"));
  auto bytes = read(dir / "l.plrl");
  const std::size_t full = bytes.size();
  bytes.resize(full / 2);
  write(dir / "l.plrl", bytes);
  const auto back = load_library(dir / "l.plrl");
  ASSERT_FALSE(back);
  EXPECT_EQ(back.error().message, (dir / "l.plrl").string() +
                                      ": truncated: " + std::to_string(full / 2) + " of " +
                                      std::to_string(full) + " bytes");
  bytes.resize(3);
  write(dir / "l.plrl", bytes);
  EXPECT_EQ(load_library(dir / "l.plrl").error().message,
            (dir / "l.plrl").string() + ": truncated: 3 bytes, a library has at least 8");
}

// The body follows a 4-byte size, so in a file read into memory it is off
// the 8-byte boundary FlatBuffers reads doubles at; the reader hands it over
// aligned, whatever the alignment of the bytes it was given.
TEST(Library, TheFramedBodyIsReadAlignedWhereverTheFileLies) {
  Library library;
  library.entries.push_back(entry("A1-3"));
  const auto framed = serialize(library);
  std::vector<std::uint64_t> storage(framed.size() / 8 + 2);
  for (std::size_t shift = 0; shift < 8; ++shift) {
    auto* at = reinterpret_cast<std::uint8_t*>(storage.data()) + shift;
    std::copy(framed.begin(), framed.end(), at);
    const auto body = unframe(at, framed.size(), framed.size(), "a library", "l.plrl");
    ASSERT_TRUE(body) << body.error().message;
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(body->data) % 8, 0u) << "shift " << shift;
    EXPECT_TRUE(std::equal(body->data, body->data + body->size, at + 4));
    const auto lib = deserialize_library(at, framed.size(), "l.plrl");
    ASSERT_TRUE(lib) << lib.error().message;
    EXPECT_EQ(lib->entries.at(0).name, "A1-3");
  }
}

// A frame whose checksum holds over a body too short to be a FlatBuffers
// buffer: the identifier test must not read past it (found by fuzzing).
TEST(Library, AnEmptyBodyIsRefusedBeforeItsIdentifierIsRead) {
  const std::vector<std::uint8_t> none;
  const auto framed = plr::frame(none.data(), 0);
  const auto back = deserialize_library(framed.data(), framed.size(), "l.plrl");
  ASSERT_FALSE(back);
  EXPECT_EQ(back.error().message, "l.plrl: bytes 4..4: 0 bytes, too short for a library");
}

TEST(Library, CorruptByteIsRefusedAsAChecksumMismatch) {
  TempDir dir;
  Library lib;
  lib.entries = {entry("A1-3")};
  ASSERT_TRUE(save_library(lib, dir / "l.plrl"));
  auto bytes = read(dir / "l.plrl");
  bytes[bytes.size() / 2] ^= 0x40;
  write(dir / "l.plrl", bytes);
  const auto back = load_library(dir / "l.plrl");
  ASSERT_FALSE(back);
  EXPECT_EQ(back.error().message, (dir / "l.plrl").string() + ": bytes 4.." +
                                      std::to_string(bytes.size() - 4) +
                                      ": checksum mismatch (corrupt)");
}

TEST(Library, AnInvalidTreeNamesItsEntry) {
  Library lib;
  lib.entries = {entry("A1-3"), entry("B1-1")};
  lib.entries[1].strategy.nodes[0].children[0].second = 5;  // no node 5
  const auto bytes = serialize(lib);
  const auto back = deserialize_library(bytes.data(), bytes.size(), "l.plrl");
  ASSERT_FALSE(back);
  EXPECT_EQ(back.error().message.rfind("l.plrl: entries[1] 'B1-1': strategy: ", 0), 0u)
      << back.error().message;
}

TEST(Library, OtherFilesAreRefused) {
  const std::vector<std::uint8_t> text{'h', 'e', 'l', 'l', 'o', ' ', 'w', 'o', 'r', 'l', 'd'};
  const auto back = deserialize_library(text.data(), text.size(), "x");
  ASSERT_FALSE(back);
  EXPECT_EQ(back.error().message, "x: bytes 0..4: size 1819043176 is over the limit of 1073741824");
}
