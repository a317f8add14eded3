#include "component/local_topics.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "component/receive_loop.hpp"

namespace rsca::component::detail {

void LocalInbox::push(LocalSample sample) {
  {
    std::lock_guard lock(mutex_);
    const std::size_t limit = depth_ == 0 ? kKeepAllLimit : depth_;
    if (queue_.size() >= limit) {
      queue_.pop_front(); // KEEP_LAST: the newest replace the oldest
      ++dropped_;
    }
    queue_.push_back(std::move(sample));
    ++pushed_;
  }
  loop_.wake_in_host();
}

std::deque<LocalSample> LocalInbox::take() {
  std::deque<LocalSample> out;
  std::lock_guard lock(mutex_);
  out.swap(queue_);
  return out;
}

std::uint64_t LocalInbox::pushed() const {
  std::lock_guard lock(mutex_);
  return pushed_;
}

std::uint64_t LocalInbox::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

void LocalTopic::add_reader(const std::shared_ptr<LocalInbox> &inbox) {
  std::lock_guard lock(mutex_);
  readers_.push_back(inbox);
}

void LocalTopic::remove_reader(const LocalInbox *inbox) {
  std::lock_guard lock(mutex_);
  std::erase_if(readers_, [&](const auto &r) { return r.get() == inbox; });
}

void LocalTopic::add_writer() {
  std::lock_guard lock(mutex_);
  ++writers_;
}

void LocalTopic::remove_writer() {
  std::lock_guard lock(mutex_);
  --writers_;
}

std::int32_t LocalTopic::readers() const {
  std::lock_guard lock(mutex_);
  return static_cast<std::int32_t>(readers_.size());
}

std::int32_t LocalTopic::writers() const {
  std::lock_guard lock(mutex_);
  return writers_;
}

std::size_t LocalTopic::publish(const LocalSample &sample) const {
  std::lock_guard lock(mutex_);
  for (const auto &inbox : readers_)
    inbox->push(sample);
  return readers_.size();
}

LocalTopics &LocalTopics::instance() {
  static LocalTopics topics;
  return topics;
}

tl::expected<std::shared_ptr<LocalTopic>, std::string> LocalTopics::join(const std::string &name,
                                                                         port::PortType type) {
  std::lock_guard lock(mutex_);
  auto &slot = topics_[name];
  if (auto topic = slot.lock()) {
    if (topic->type() != type)
      return tl::unexpected(fmt::format("local topic \"{}\" carries {}, not {}", name,
                                        port::to_string(topic->type()), port::to_string(type)));
    return topic;
  }
  std::erase_if(topics_, [](const auto &entry) { return entry.second.expired(); });
  auto topic = std::make_shared<LocalTopic>(type);
  topics_[name] = topic;
  return topic;
}

} // namespace rsca::component::detail
