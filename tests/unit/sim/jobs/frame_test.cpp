#include <gtest/gtest.h>
#include <unistd.h>

#include <plr/frame.hpp>

#include <string>

namespace {

std::vector<std::uint8_t> bytes(const std::string& s) {
  return {s.begin(), s.end()};
}

TEST(Frame, RoundTripsAndChecksItsCrc) {
  const auto payload = bytes("a payload of some bytes");
  auto framed = plr::frame(payload.data(), payload.size());
  ASSERT_EQ(framed.size(), payload.size() + plr::kFrameOverhead);
  auto back = plr::unframe(framed.data(), framed.size(), 1024, "test");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(std::vector<std::uint8_t>(back->data, back->data + back->size), payload);

  framed[6] ^= 0x01;
  auto altered = plr::unframe(framed.data(), framed.size(), 1024, "test");
  ASSERT_FALSE(altered);
  EXPECT_NE(altered.error().message.find("checksum"), std::string::npos);
}

TEST(Frame, RefusesCutShortOversizedAndTrailingBytes) {
  const auto payload = bytes("0123456789");
  auto framed = plr::frame(payload.data(), payload.size());
  EXPECT_FALSE(plr::unframe(framed.data(), framed.size() - 1, 1024, "t"));
  EXPECT_FALSE(plr::unframe(framed.data(), 3, 1024, "t"));
  EXPECT_FALSE(plr::unframe(framed.data(), framed.size(), 9, "t"));
  framed.push_back(0);
  EXPECT_FALSE(plr::unframe(framed.data(), framed.size(), 1024, "t"));
}

TEST(Frame, Crc32IsZipsCrc) {
  const auto check = bytes("123456789");
  EXPECT_EQ(plr::crc32(check.data(), check.size()), 0xcbf43926u);
}

TEST(FrameReader, ReadsFramesThatComeInPieces) {
  const auto a = bytes("first"), b = bytes("second, longer");
  auto stream = plr::frame(a.data(), a.size());
  const auto fb = plr::frame(b.data(), b.size());
  stream.insert(stream.end(), fb.begin(), fb.end());
  plr::FrameReader reader(1024, "test");
  std::vector<std::vector<std::uint8_t>> got;
  for (const std::uint8_t byte : stream) {
    reader.feed(&byte, 1);
    auto next = reader.next();
    ASSERT_TRUE(next) << next.error().message;
    if (*next) got.push_back(**next);
  }
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0], a);
  EXPECT_EQ(got[1], b);
  EXPECT_EQ(reader.pending(), 0u);
}

TEST(FrameReader, ReadsAPipeToItsEndAndRefusesATornFrame) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const auto a = bytes("whole");
  const auto framed = plr::frame(a.data(), a.size());
  ASSERT_TRUE(plr::write_all(fds[1], framed));
  ASSERT_TRUE(plr::write_all(fds[1], framed.data(), 5));
  ::close(fds[1]);
  plr::FrameReader reader(1024, "pipe");
  auto first = reader.read(fds[0]);
  ASSERT_TRUE(first && *first);
  EXPECT_EQ(**first, a);
  auto torn = reader.read(fds[0]);
  ASSERT_FALSE(torn);
  EXPECT_NE(torn.error().message.find("ends inside a frame"), std::string::npos);
  ::close(fds[0]);
}

}  // namespace
