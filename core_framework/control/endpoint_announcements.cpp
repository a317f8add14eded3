// Announcements: what an endpoint says about itself, and what it hears of others.
#include "control/endpoint_impl.hpp"

#include <algorithm>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "control.h" // generated from dds/control.idl
#include "protocol/topics.hpp"

namespace rsca::control {

using namespace detail;

void Endpoint::Impl::take_announcements() {
  void *samples[kTakeBatch] = {nullptr};
  dds_sample_info_t infos[kTakeBatch];
  for (;;) {
    const dds_return_t n =
        dds_take(announcement_reader.get(), samples, infos, kTakeBatch, kTakeBatch);
    if (n <= 0)
      return;
    const AnnouncementHandler &handler = options.on_announcement;
    for (dds_return_t i = 0; i < n; ++i) {
      const auto *a = static_cast<const rsca_ctl_Announcement *>(samples[i]);
      const std::string announcer = str(a->announcer);
      AnnouncementEvent event;
      // A withdrawal's sample, whatever the instance's state now (a reused slot is alive again).
      const bool withdrawal = infos[i].valid_data && str(a->kind) == protocol::kWithdrawnKind;
      if (infos[i].valid_data && infos[i].instance_state == DDS_IST_ALIVE && !withdrawal) {
        event.kind = AnnouncementEvent::Kind::Alive;
        event.address = str(a->address);
        event.endpoint_kind = str(a->kind);
        event.body = parse_body(a->body).value_or(Json(Json::value_t::discarded));
        // The slot held another address: that one was withdrawn, its disposal overwritten.
        if (auto before = heard_slots.heard(announcer, a->slot, event.address))
          handler(AnnouncementEvent{AnnouncementEvent::Kind::Gone,
                                    std::move(*before),
                                    {},
                                    {},
                                    /*withdrawn=*/true});
      } else if (infos[i].instance_state != DDS_IST_ALIVE || withdrawal) {
        auto went = heard_slots.gone(announcer, a->slot);
        if (!went)
          continue; // a slot freed before this endpoint heard it
        event.kind = AnnouncementEvent::Kind::Gone;
        event.address = std::move(*went);
        event.withdrawn = withdrawal;
      } else {
        continue;
      }
      // An address served by another endpoint on its behalf (a node relaying for a process it
      // started) says which: calls to it go there.
      if (event.kind == AnnouncementEvent::Kind::Alive && event.body.is_object())
        if (auto via = event.body.find(kAnnouncedVia);
            via != event.body.end() && via->is_string() && !via->get<std::string>().empty()) {
          std::lock_guard lock(routes_mutex);
          routes[event.address] = via->get<std::string>();
        }
      if (event.kind == AnnouncementEvent::Kind::Alive &&
          std::find(options.prepare_kinds.begin(), options.prepare_kinds.end(),
                    event.endpoint_kind) != options.prepare_kinds.end())
        request_ways->writer_for(route_of(event.address)); // not waited for
      handler(event);
    }
    dds_return_loan(announcement_reader.get(), samples, n);
  }
}

Expected<void> Endpoint::Impl::announce(const std::string &as, const std::string &kind,
                                        const Json &body) {
  std::lock_guard lock(announcement_mutex);
  if (!announcement_writer) {
    auto qos = announcement_qos();
    auto w = dds::checked(
        dds_create_writer(participant->get(), announcement_topic.get(), qos.get(), nullptr),
        "creating the announcement writer");
    if (!w)
      return tl::unexpected(w.error());
    announcement_writer = std::move(*w);
  }
  const std::string text = body.dump();
  rsca_ctl_Announcement a{};
  a.announcer = const_cast<char *>(address.c_str());
  const bool fresh = !announcer_slots.has(as);
  a.slot = announcer_slots.slot_for(as);
  a.address = const_cast<char *>(as.c_str());
  a.kind = const_cast<char *>(kind.c_str());
  a.body = const_cast<char *>(text.c_str());
  if (dds_return_t rc = dds_write(announcement_writer.get(), &a); rc < 0) {
    if (fresh)
      announcer_slots.release(as); // nothing was written in it
    return tl::unexpected(dds::dds_error(rc, "announcing"));
  }
  return {};
}

void Endpoint::Impl::withdraw(const std::string &as) {
  std::lock_guard lock(announcement_mutex);
  if (!announcement_writer)
    return;
  const auto slot = announcer_slots.release(as);
  if (!slot)
    return;
  rsca_ctl_Announcement a{};
  a.announcer = const_cast<char *>(address.c_str());
  a.slot = *slot;
  a.address = const_cast<char *>("");
  a.kind = const_cast<char *>(protocol::kWithdrawnKind);
  a.body = const_cast<char *>("");
  dds_writedispose(announcement_writer.get(), &a); // with data: withdrawn, not lost
  // And let go of the instance, so that readers see it without writers until the slot is reused.
  dds_unregister_instance(announcement_writer.get(), &a);
}

Expected<void> Endpoint::announce(const std::string &kind, const Json &body) {
  return impl_->announce(impl_->address, kind, body);
}

void Endpoint::withdraw() {
  impl_->withdraw(impl_->address);
}

Expected<void> Endpoint::announce(const std::string &alias, const std::string &kind,
                                  const Json &body) {
  return impl_->announce(alias, kind, body);
}

void Endpoint::withdraw(const std::string &alias) {
  impl_->withdraw(alias);
}

} // namespace rsca::control
