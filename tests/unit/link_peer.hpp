// A test's end of a node link (protocol/node_link.hpp): writes frames and reads them whole, as
// the node (node_link_test) or as the process (process_links_test).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <poll.h>

#include <catch2/catch.hpp>

#include "control/link_socket.hpp"

namespace rsca::test {

struct LinkPeer {
  process::Fd fd;
  std::unique_ptr<control::LinkWriter> writer;
  control::FrameReader reader;
  std::vector<protocol::link::Frame> frames;

  explicit LinkPeer(process::Fd end)
      : fd(std::move(end)), writer(std::make_unique<control::LinkWriter>(fd.get())) {}

  // The next frame, which must come within 10 s.
  protocol::link::Frame next() {
    while (frames.empty()) {
      pollfd readable{fd.get(), POLLIN, 0};
      REQUIRE(::poll(&readable, 1, 10000) == 1);
      std::string why;
      REQUIRE(reader.read_from(fd.get(), frames, why));
    }
    auto f = std::move(frames.front());
    frames.erase(frames.begin());
    return f;
  }
};

} // namespace rsca::test
