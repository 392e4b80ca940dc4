// The simulation results a generation has paid for, kept on disk so that a
// generation killed mid-run and started again runs none of them twice: an
// append-only file of records [u32 size][u32 CRC-32][u64 key][a SimResult
// frame (sim_work.hpp)]. A record a kill cut short, or one that does not
// check, ends the journal: the file is cut back to the last good record.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <unordered_map>

#include "truck/simulator.hpp"

namespace plr::generator {

class Journal {
 public:
  static plr::Expected<std::unique_ptr<Journal>> open(const std::filesystem::path& file);
  ~Journal();

  // What the file held when opened, by work_key().
  std::unordered_map<std::uint64_t, SimOutcome> take_loaded() { return std::move(loaded_); }
  std::size_t loaded_count() const { return loaded_count_; }
  std::size_t dropped_bytes() const { return dropped_bytes_; }

  plr::Status append(std::uint64_t key, const SimOutcome& outcome);
  // On disk for good (fsync), e.g. after each batch.
  plr::Status sync();

 private:
  Journal() = default;
  std::FILE* file_ = nullptr;
  std::filesystem::path path_;
  std::unordered_map<std::uint64_t, SimOutcome> loaded_;
  std::size_t loaded_count_ = 0, dropped_bytes_ = 0;
};

}  // namespace plr::generator
