// The I/O command on the wire: what encode writes, decode reads back, and
// decode refuses what a forward_command_controller's peer must not send.
#include <plr/ros2/wire.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace {

using plr::ros2::IoCommand;

struct Encoded {
  explicit Encoded(const IoCommand& io) { plr::ros2::encode(io, wire.msg); }
  plr::ros2::Wire<std_msgs_msg_dds__Float64MultiArray_> wire{
      &std_msgs_msg_dds__Float64MultiArray__desc};
};

TEST(IoWire, ACommandReadsBackAsWritten) {
  const IoCommand io{true, false, {true, false, true}};
  const Encoded e(io);
  const auto& w = e.wire;
  ASSERT_EQ(w.msg.data._length, 5u);
  EXPECT_EQ(w.msg.data._buffer[0], 1.0);
  EXPECT_EQ(w.msg.data._buffer[1], 0.0);
  EXPECT_EQ(w.msg.data._buffer[3], 0.0);
  ASSERT_EQ(w.msg.layout.dim._length, 1u);
  EXPECT_STREQ(w.msg.layout.dim._buffer[0].label, "io");
  EXPECT_EQ(w.msg.layout.dim._buffer[0].size, 5u);
  const auto back = plr::ros2::decode(w.msg);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(*back, io);
}

TEST(IoWire, ValuesOtherThanZeroAndOneAndShortCommandsAreRefused) {
  Encoded e(IoCommand{true, true, {true, true}});
  auto& w = e.wire;
  w.msg.data._buffer[3] = 0.5;
  auto r = plr::ros2::decode(w.msg);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "io.data[3]: 0.5 is neither 0 nor 1");
  w.msg.data._buffer[3] = std::nan("");
  r = plr::ros2::decode(w.msg);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "io.data[3]: not a finite number");
  w.msg.data._length = 1;
  r = plr::ros2::decode(w.msg);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "io.data: 1 values, the vacuum and the conveyor at least");
}

}  // namespace
