#include <plr/message.hpp>
#include <plr/messages.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

namespace {

std::vector<std::uint8_t> world_with_trailer(double width, double height, double depth) {
  flatbuffers::FlatBufferBuilder fbb;
  const plr::msg::Vec3 size(width, height, depth);
  plr::msg::WorldStateBuilder b(fbb);
  b.add_trailer_size(&size);
  fbb.Finish(b.Finish());
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

flatbuffers::DetachedBuffer request_nesting(const std::vector<std::uint8_t>& world) {
  flatbuffers::FlatBufferBuilder fbb;
  const auto nested = plr::create_nested(fbb, world.data(), world.size());
  fbb.Finish(plr::msg::CreateNextStrategyRequest(fbb, nested));
  return fbb.Release();
}

TEST(NestedMessage, WriterAlignsItForReadingInPlace) {
  const auto world = world_with_trailer(2.4, 2.6, 16);
  const auto request = request_nesting(world);
  const auto* r = flatbuffers::GetRoot<plr::msg::NextStrategyRequest>(request.data());
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(r->world()->data()) % plr::kNestedAlignment, 0u);

  std::vector<std::uint64_t> storage;
  const auto* w = plr::read_nested<plr::msg::WorldState>(r->world(), storage);
  ASSERT_NE(w, nullptr);
  EXPECT_TRUE(storage.empty()) << "an aligned nested message is read in place";
  EXPECT_DOUBLE_EQ(w->trailer_size()->y(), 2.6);
}

TEST(NestedMessage, ReaderCopiesAMisalignedOne) {
  const auto request = request_nesting(world_with_trailer(2.4, 2.6, 16));
  // The same bytes 4 bytes off an 8-byte boundary, as a foreign writer may send them.
  std::vector<std::uint64_t> shifted(request.size() / 8 + 2);
  auto* at = reinterpret_cast<std::uint8_t*>(shifted.data()) + 4;
  std::memcpy(at, request.data(), request.size());
  const auto* r = flatbuffers::GetRoot<plr::msg::NextStrategyRequest>(at);
  ASSERT_NE(reinterpret_cast<std::uintptr_t>(r->world()->data()) % plr::kNestedAlignment, 0u);

  std::vector<std::uint64_t> storage;
  const auto* w = plr::read_nested<plr::msg::WorldState>(r->world(), storage);
  ASSERT_NE(w, nullptr);
  EXPECT_FALSE(storage.empty());
  EXPECT_DOUBLE_EQ(w->trailer_size()->z(), 16.0);
}

TEST(NestedMessage, ReaderRefusesGarbageAndAbsence) {
  std::vector<std::uint64_t> storage;
  EXPECT_EQ(plr::read_nested<plr::msg::WorldState>(nullptr, storage), nullptr);

  const std::vector<std::uint8_t> garbage(40, 0xff);
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(plr::msg::CreateNextStrategyRequest(
      fbb, plr::create_nested(fbb, garbage.data(), garbage.size())));
  const auto* r = flatbuffers::GetRoot<plr::msg::NextStrategyRequest>(fbb.GetBufferPointer());
  EXPECT_EQ(plr::read_nested<plr::msg::WorldState>(r->world(), storage), nullptr);
}

}  // namespace
