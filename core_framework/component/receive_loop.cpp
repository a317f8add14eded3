#include "component/receive_loop.hpp"

namespace rsca::component::detail {
namespace {

// The longest the thread waits before it polls again: the owner then also looks for connection
// problems (component/host.cpp), so this bounds how late a deadline miss is seen.
constexpr dds_duration_t kWakeInterval = DDS_MSECS(100);

} // namespace

Expected<std::unique_ptr<ReceiveLoop>> ReceiveLoop::start(dds_entity_t participant,
                                                          std::function<void()> poll) {
  auto waitset = dds::checked(dds_create_waitset(participant), "creating the receive waitset");
  if (!waitset)
    return tl::unexpected(waitset.error());
  auto guard =
      dds::checked(dds_create_guardcondition(participant), "creating the receive guard condition");
  if (!guard)
    return tl::unexpected(guard.error());
  if (dds_return_t rc = dds_waitset_attach(waitset->get(), guard->get(), 0); rc < 0)
    return tl::unexpected(dds::dds_error(rc, "attaching the receive guard condition"));
  std::unique_ptr<ReceiveLoop> loop(
      new ReceiveLoop(std::move(*waitset), std::move(*guard), std::move(poll)));
  loop->thread_ = std::thread([raw = loop.get()] { raw->run(); });
  return loop;
}

ReceiveLoop::ReceiveLoop(dds::Entity waitset, dds::Entity guard, std::function<void()> poll)
    : waitset_(std::move(waitset)), guard_(std::move(guard)), poll_(std::move(poll)) {}

ReceiveLoop::~ReceiveLoop() {
  stop();
}

void ReceiveLoop::stop() {
  stopping_ = true;
  dds_set_guardcondition(guard_.get(), true);
  if (thread_.joinable())
    thread_.join();
}

Expected<void> ReceiveLoop::attach(dds_entity_t condition) {
  if (dds_return_t rc = dds_waitset_attach(waitset_.get(), condition, condition); rc < 0)
    return tl::unexpected(dds::dds_error(rc, "attaching a read condition"));
  return {};
}

void ReceiveLoop::detach(dds_entity_t condition) {
  dds_waitset_detach(waitset_.get(), condition);
}

void ReceiveLoop::run() {
  while (!stopping_.load()) {
    // The guard is set only to stop the loop, which then ends: it is never reset.
    dds_waitset_wait(waitset_.get(), nullptr, 0, kWakeInterval);
    if (stopping_.load())
      return;
    poll_();
  }
}

} // namespace rsca::component::detail
