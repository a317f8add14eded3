// A connection's samples on a TCP stream between its two processes (transport="tcp",
// docs/profiles.md): for a point-to-point loop that must not pay DDS's thread hand-offs and
// acknowledgements (RangeStop's safety loop across hosts, docs/measurements.md). The reader
// listens on its host's address (the DDS interface's); the writer connects and first sends the
// token the domain gave both ends; then each sample is one frame, a 32-bit length and the
// sample's ring record (component/port_record.hpp). Nothing from the network is trusted: a frame
// longer than kMaxFrame, a wrong token or a token not sent within kTokenTimeout closes the stream.
// The token travels over the control plane in clear until that is authenticated (DDS Security), so
// it admits one writer once: the reader stops listening when its writer has sent it, and a
// connection whose writer has gone is not taken up again by anyone who learnt the token (the
// domain wires a new connection, with a new token, instead).
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <tl/expected.hpp>

#include "process/fd.hpp"

namespace rsca::component::detail {

// The longest frame a stream takes (a record of a port value): 16 MiB.
inline constexpr std::uint32_t kMaxFrame = 16u << 20;
// How long an accepted stream has to send its token.
inline constexpr std::chrono::milliseconds kTokenTimeout{2000};
// A token: 8 to 64 characters [0-9a-f].
bool valid_token(const std::string &token);

// The IPv4 address a reader listens on: that of the network interface DDS uses on this host
// (RSCA_DDS_INTERFACE, dds/dds_settings.hpp), or loopback when that is "lo" or has none.
std::string listen_address();

// The reading end: listens until one writer has sent the token, then closes its listening socket
// and hands each of that writer's frames to `on_frame` on its own thread; once that writer has
// gone the stream is spent. `on_frame` must not wait for the thread that destroys the stream.
class TcpReceiver {
public:
  using OnFrame = std::function<void(const std::byte *data, std::size_t bytes)>;
  static tl::expected<std::unique_ptr<TcpReceiver>, std::string>
  listen(const std::string &address, std::string token, OnFrame on_frame);
  ~TcpReceiver(); // stops the thread: no on_frame runs once it returns
  TcpReceiver(const TcpReceiver &) = delete;
  TcpReceiver &operator=(const TcpReceiver &) = delete;

  // "address:port", for the writer.
  const std::string &endpoint() const { return endpoint_; }
  // 1 while a writer that sent the token is connected, else 0.
  std::int32_t writers() const { return writers_.load(std::memory_order_relaxed); }
  // Streams closed for a wrong or missing token, or a frame too long.
  std::uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }
  // True once the writer that sent the token has gone: nothing more arrives on this stream.
  bool spent() const { return spent_.load(std::memory_order_relaxed); }

private:
  TcpReceiver(process::Fd listening, process::Fd stop, std::string endpoint, std::string token,
              OnFrame on_frame);
  void run();
  process::Fd accept_writer();
  bool take_token(int fd);
  void read_frames(int fd);

  process::Fd listening_;
  process::Fd stop_; // an eventfd: written to stop the thread
  std::string endpoint_;
  std::string token_;
  OnFrame on_frame_;
  std::atomic<std::int32_t> writers_{0};
  std::atomic<std::uint64_t> refused_{0};
  std::atomic<bool> spent_{false};
  std::thread thread_;
};

// The writing end: one connected stream; send() is safe from any thread.
class TcpSender {
public:
  static tl::expected<std::unique_ptr<TcpSender>, std::string>
  connect(const std::string &endpoint, const std::string &token, std::chrono::milliseconds timeout);

  // Sends one frame of `bytes` made by `fill(std::byte *)`. A reader that does not take what it
  // is sent for kSendTimeout breaks the stream (the write fails, and every later one).
  tl::expected<void, std::string> send(std::size_t bytes,
                                       const std::function<void(std::byte *)> &fill);
  // 1 while the stream is up, else 0.
  std::int32_t readers() const { return broken_.load(std::memory_order_relaxed) ? 0 : 1; }

  static constexpr std::chrono::milliseconds kSendTimeout{200};

private:
  explicit TcpSender(process::Fd fd) : fd_(std::move(fd)) {}

  std::mutex mutex_; // one frame at a time
  process::Fd fd_;
  std::vector<std::byte> buffer_;
  std::atomic<bool> broken_{false};
};

} // namespace rsca::component::detail
