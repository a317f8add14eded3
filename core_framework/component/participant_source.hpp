// The DDS participant of a component process, joined only when a data connection needs it. A
// process its node started reaches the control plane through its node (control/node_link.hpp):
// it has no participant, and no UDP socket, unless one of its connections goes over DDS. The
// components of one component host share one source, hence one participant.
#pragma once

#include <memory>
#include <mutex>
#include <thread>

#include "common/diagnostic.hpp"
#include "dds/participant.hpp"

namespace rsca::component {

class ParticipantSource {
public:
  // A source of `given` (a node's devices, a process that joined DDS for its control), or, when
  // null, of a participant made from the environment at the first get().
  explicit ParticipantSource(std::shared_ptr<dds::Participant> given = nullptr)
      : participant_(std::move(given)) {}
  ~ParticipantSource() {
    if (joining_.joinable())
      joining_.join();
  }
  ParticipantSource(const ParticipantSource &) = delete;
  ParticipantSource &operator=(const ParticipantSource &) = delete;

  // Starts joining DDS now, on a thread of its own, for a process that will need it (it has data
  // ports): DDS discovery of the new participant then overlaps with the launch's steps before
  // `connect` instead of adding to it (measured: docs/measurements.md). Once only.
  void join_in_background() {
    std::lock_guard lock(mutex_);
    if (participant_ || joining_.joinable())
      return;
    // A failure is not kept: get() tries again, and says why, for whoever needs the participant.
    joining_ = std::thread([this] { [[maybe_unused]] auto joined = get(); });
  }

  Expected<std::shared_ptr<dds::Participant>> get() {
    std::lock_guard lock(mutex_);
    if (participant_)
      return participant_;
    auto made = dds::Participant::create(dds::DdsSettings::from_environment());
    if (!made)
      return tl::unexpected(made.error());
    participant_ = std::move(*made);
    return participant_;
  }

  bool joined() const {
    std::lock_guard lock(mutex_);
    return participant_ != nullptr;
  }

private:
  mutable std::mutex mutex_;
  std::shared_ptr<dds::Participant> participant_;
  std::thread joining_;
};

} // namespace rsca::component
