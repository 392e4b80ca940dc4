// A result store: a folder holding each finished job's result as
// results/<key>.result (a JobReply in a CRC-checked frame, written
// atomically) and what its process wrote to stderr as logs/<key>.log. A job
// whose result file is here is not run again; a file that does not check
// (cut short, altered, another key's) counts as missing.
#pragma once

#include <plr/expected.hpp>

#include <filesystem>
#include <optional>
#include <string>

#include "plr/jobs/job.hpp"

namespace plr::jobs {

class Store {
 public:
  // Creates the folder and its results/ and logs/ when missing.
  static plr::Expected<Store> open(const std::filesystem::path& dir);

  const std::filesystem::path& dir() const { return dir_; }
  std::filesystem::path result_file(const std::string& key) const;
  std::filesystem::path log_file(const std::string& key) const;
  std::filesystem::path logs() const { return dir_ / "logs"; }

  // The result stored under `key` (stored = true); nullopt when there is
  // none or it is damaged.
  std::optional<Result> load(const std::string& key) const;
  // Replaces `result.key`'s file atomically (temporary file, fsync, rename).
  plr::Status save(const Result& result) const;

 private:
  explicit Store(std::filesystem::path dir) : dir_(std::move(dir)) {}
  std::filesystem::path dir_;
};

}  // namespace plr::jobs
