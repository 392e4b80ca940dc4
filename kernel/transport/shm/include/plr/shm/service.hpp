// Services across processes: request/reply over the same rings as topics.
// The server's segment holds one channel per client: a request ring (client
// writes, server reads in place) and a reply ring (server writes, client reads
// in place). Every request carries a correlation id that its reply echoes.
//
// Threading: ServiceServer: one thread at a time. ServiceClient: send side
// (loan_request/send_request) one thread at a time, take_reply() one thread at
// a time (may be another thread). Loans/Samples as in topic.hpp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "plr/shm/topic.hpp"
#include "plr/shm/types.hpp"

namespace plr::shm {

struct ServiceConfig {
  std::uint32_t slot_count = 4;         // requests (and replies) in flight per client
  std::uint32_t slot_size = 64 * 1024;  // bytes per request / reply
  std::uint32_t max_clients = 8;        // 1..64
  WaitMode wait_mode = WaitMode::kBlocking;
};

// Where a reply goes; stays valid after the request's Sample is dropped.
struct ReplyTo {
  std::uint32_t channel = 0;
  std::uint32_t generation = 0;
  std::uint64_t correlation_id = 0;
};

struct Request {
  Sample sample;  // info().correlation_id identifies the call
  ReplyTo reply_to;
};

class ServiceServer {
 public:
  ServiceServer(ServiceServer&&) noexcept;
  ServiceServer& operator=(ServiceServer&&) noexcept;
  // Marks the segment closed (clients' pending calls fail with kClosed), unlinks it.
  ~ServiceServer();

  // Next request from any client (round robin). kNoData / kTimeout.
  // While waiting, channels of dead or departed clients are freed.
  Result<Request> take_request(Timeout timeout = kNoWait) noexcept;
  // kUnknownClient if the client left (or its channel was reused), kPeerDead
  // if it died; waits up to timeout when the client's reply ring is full.
  Result<Loan> loan_reply(const ReplyTo& to, std::size_t max_size,
                          Timeout timeout = kNoWait) noexcept;
  Result<void> send_reply(Loan&& loan, const ReplyTo& to, MessageType type, std::size_t offset,
                          std::size_t size) noexcept;
  // Frees channels of clients that died or left. Returns how many.
  std::size_t reclaim_dead_clients() noexcept;
  std::size_t client_count() const noexcept;
  const std::string& segment_name() const noexcept;

  struct Impl;

 private:
  friend class ServiceServerBuilder;
  explicit ServiceServer(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

class ServiceServerBuilder {
 public:
  ServiceServerBuilder& run_id(std::string_view v) {
    run_id_ = v;
    return *this;
  }
  ServiceServerBuilder& service(std::string_view v) {
    service_ = v;
    return *this;
  }
  ServiceServerBuilder& config(const ServiceConfig& c) {
    config_ = c;
    return *this;
  }
  Result<ServiceServer> create() const;

 private:
  std::string run_id_, service_;
  ServiceConfig config_;
};

class ServiceClient {
 public:
  ServiceClient(ServiceClient&&) noexcept;
  ServiceClient& operator=(ServiceClient&&) noexcept;
  ~ServiceClient();  // hands its channel back to the server

  // Waits up to timeout when the server lags (request ring full).
  Result<Loan> loan_request(std::size_t max_size, Timeout timeout = kNoWait) noexcept;
  // Sends buffer()[offset, offset + size); returns the correlation id.
  // kPeerDead / kClosed at once if the server is gone.
  Result<std::uint64_t> send_request(Loan&& loan, MessageType type, std::size_t offset,
                                     std::size_t size) noexcept;
  // Next reply (match info().correlation_id). While requests are pending and
  // the server dies: kPeerDead at once if already dead, else within 5 ms.
  Result<Sample> take_reply(Timeout timeout = kNoWait) noexcept;
  // Requests sent minus replies taken.
  std::uint64_t pending() const noexcept;
  Result<void> server_alive() const noexcept;
  const ServiceConfig& config() const noexcept;

  struct Impl;

 private:
  friend class ServiceClientBuilder;
  explicit ServiceClient(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

class ServiceClientBuilder {
 public:
  ServiceClientBuilder& run_id(std::string_view v) {
    run_id_ = v;
    return *this;
  }
  ServiceClientBuilder& service(std::string_view v) {
    service_ = v;
    return *this;
  }
  // kNotFound until the server is up; kTooManyClients if every channel is taken.
  Result<ServiceClient> create() const;

 private:
  std::string run_id_, service_;
};

// Bytes of /dev/shm the segment of a service with this config takes (whole pages).
std::size_t segment_bytes(const ServiceConfig& config) noexcept;

}  // namespace plr::shm
