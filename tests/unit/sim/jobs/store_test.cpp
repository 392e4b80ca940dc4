#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "plr/jobs/store.hpp"

namespace fs = std::filesystem;

namespace {

class StoreTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_jobs_store_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(StoreTest, KeepsAResultAndReadsItBackAsStored) {
  auto store = plr::jobs::Store::open(dir_);
  ASSERT_TRUE(store) << store.error().message;
  EXPECT_FALSE(store->load("one"));
  ASSERT_TRUE(store->save({"one", true, {1, 2, 3}, "", 0.5, 1, false}));
  auto back = store->load("one");
  ASSERT_TRUE(back);
  EXPECT_TRUE(back->stored);
  EXPECT_TRUE(back->ok);
  EXPECT_EQ(back->output, (plr::jobs::Bytes{1, 2, 3}));
  // Written atomically: no temporary file is left beside it.
  std::size_t files = 0;
  for (const auto& f : fs::directory_iterator(dir_ / "results")) {
    ++files;
    EXPECT_EQ(f.path().filename(), "one.result");
  }
  EXPECT_EQ(files, 1u);
  EXPECT_TRUE(fs::is_directory(store->logs()));
}

TEST_F(StoreTest, ADamagedResultCountsAsMissing) {
  auto store = plr::jobs::Store::open(dir_);
  ASSERT_TRUE(store);
  ASSERT_TRUE(store->save({"cut", true, plr::jobs::Bytes(100, 1), "", 0, 1, false}));
  ASSERT_TRUE(store->save({"flipped", true, plr::jobs::Bytes(100, 1), "", 0, 1, false}));
  ASSERT_TRUE(store->save({"other", true, {}, "", 0, 1, false}));
  fs::resize_file(store->result_file("cut"), fs::file_size(store->result_file("cut")) - 3);
  {
    std::fstream f(store->result_file("flipped"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(40);
    f.put('\x55');
  }
  fs::copy_file(store->result_file("other"), store->result_file("renamed"));
  EXPECT_FALSE(store->load("cut"));
  EXPECT_FALSE(store->load("flipped"));
  EXPECT_FALSE(store->load("renamed"));  // the file holds another key's result
  EXPECT_TRUE(store->load("other"));
}

TEST_F(StoreTest, RefusesAKeyThatIsNoFileName) {
  auto store = plr::jobs::Store::open(dir_);
  ASSERT_TRUE(store);
  EXPECT_FALSE(store->save({"../escape", true, {}, "", 0, 1, false}));
}

}  // namespace
