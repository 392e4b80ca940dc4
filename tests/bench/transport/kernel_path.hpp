// The kernel's publish path across processes (bus + shared-memory bridge, as
// in `plr run` with two hosts): what a publish costs the publishing thread,
// and the one-way latency to a subscriber in the other process, for a message
// built in a loaned slot, copied into one, or built on the heap.
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace plr::bench {

struct KernelRow {
  std::string path;
  std::size_t size = 0;
  bool ok = false;
  std::string error;
  std::size_t messages = 0;
  double publish_p50_us = 0, publish_p99_us = 0;  // loan (or alloc) .. publish() returned
  double oneway_p50_us = 0, oneway_p99_us = 0;    // loan .. other process's callback
  std::uint64_t sent_in_place = 0, sent_copied = 0;
};

std::vector<KernelRow> run_kernel_path(bool quick, const std::string& run_id);
const char* kernel_path_description();
void print(const KernelRow& r);
nlohmann::json to_json(const KernelRow& r);

}  // namespace plr::bench
