// A shared-memory segment: private to its user (0600), opened only when it
// is what the opener expects, replaced when its owner died, kept when not.
#include "segment.hpp"
#include "layout.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

namespace plr::shm::detail {
namespace {

using test::unique_run_id;

class SegmentTest : public ::testing::Test {
 protected:
  void TearDown() override { (void)remove_run_segments(run_); }
  const std::string run_ = unique_run_id();
  const std::string name_ = topic_segment_name(run_, "camera");
};

TEST_F(SegmentTest, CreatedPrivateAndOpenedOnlyOnceStamped) {
  auto s = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(s) << to_string(s.error());
  EXPECT_EQ(test::segment_mode(name_), 0600u);
  EXPECT_EQ(s->owner().pid, ::getpid());
  const auto early = Segment::open(name_, SegmentKind::kTopic, "camera");
  ASSERT_FALSE(early);
  EXPECT_EQ(early.error(), Error::kNotFound) << "not stamped yet";
  s->publish_header();
  auto opened = Segment::open(name_, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(opened) << to_string(opened.error());
  EXPECT_EQ(opened->size(), 4096u);
  EXPECT_EQ(opened->owner().pid, ::getpid());
}

TEST_F(SegmentTest, AnotherKindOrNameIsIncompatible) {
  auto s = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(s);
  s->publish_header();
  const auto kind = Segment::open(name_, SegmentKind::kService, "camera");
  ASSERT_FALSE(kind);
  EXPECT_EQ(kind.error(), Error::kIncompatible);
  const auto other = Segment::open(name_, SegmentKind::kTopic, "lidar");
  ASSERT_FALSE(other);
  EXPECT_EQ(other.error(), Error::kIncompatible) << "a hash collision is caught by the name";
}

TEST_F(SegmentTest, ALiveOwnersSegmentIsKeptADeadOnesReplaced) {
  auto s = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(s);
  s->publish_header();
  const auto again = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_FALSE(again);
  EXPECT_EQ(again.error(), Error::kAlreadyExists);
  // A child creates the segment and dies without removing it.
  (void)remove_run_segments(run_);
  const pid_t child = test::fork_child([&] {
    auto left = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
    if (!left) return 1;
    left->publish_header();
    return 0;
  });
  ASSERT_EQ(test::wait_child(child), 0);
  auto taken_over = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(taken_over) << to_string(taken_over.error());
}

// A host killed while it made its segment (before the magic) left one that
// counted as "owned by a live process" for 5 s; its restart then ran without it.
TEST_F(SegmentTest, ACreatorKilledBeforePublishingLeavesNothingThatBlocks) {
  const pid_t child = test::fork_child([&] {
    auto half = Segment::create(name_, 1 << 20, SegmentKind::kTopic, "camera");
    return half ? 0 : 1;  // exits before publish_header()
  });
  ASSERT_EQ(test::wait_child(child), 0);
  auto taken_over = Segment::create(name_, 1 << 20, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(taken_over) << to_string(taken_over.error());
  EXPECT_EQ(test::run_segments(run_).size(), 1u) << "no temporary name is left";
}

TEST_F(SegmentTest, UnlinkRemovesOnlyItsOwnObject) {
  auto s = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(s);
  s->unlink();
  EXPECT_TRUE(test::run_segments(run_).empty());
  auto next = Segment::create(name_, 4096, SegmentKind::kTopic, "camera");
  ASSERT_TRUE(next);
  s->unlink();
  EXPECT_EQ(test::run_segments(run_).size(), 1u) << "the name now refers to another segment";
}

TEST_F(SegmentTest, BadArgumentsAreRefused) {
  EXPECT_EQ(Segment::create(name_, 8, SegmentKind::kTopic, "camera").error(),
            Error::kInvalidArgument)
      << "smaller than its header";
  EXPECT_EQ(Segment::create(name_, 4096, SegmentKind::kTopic, "").error(), Error::kInvalidArgument);
  EXPECT_EQ(Segment::open(name_, SegmentKind::kTopic, "camera").error(), Error::kNotFound);
}

}  // namespace
}  // namespace plr::shm::detail
