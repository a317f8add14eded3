#include "control/name_holder.hpp"

#include <unistd.h>

#include <fstream>

#include <spdlog/spdlog.h>

#include "common/host_name.hpp"
#include "control.h" // generated from dds/control.idl
#include "control/endpoint_impl.hpp"

namespace rsca::control {
namespace {

// The program a process runs, as the kernel names it (its first 15 bytes).
std::string program_of(const std::string &pid) {
  std::ifstream in("/proc/" + pid + "/comm");
  std::string name;
  std::getline(in, name);
  return name;
}

// Whether process `pid` has exited and waits for its parent to reap it: a zombie still has its
// comm, but nothing of it runs.
bool zombie(const std::string &pid) {
  std::ifstream in("/proc/" + pid + "/stat");
  std::string stat;
  std::getline(in, stat);
  const auto end_of_name = stat.rfind(')'); // the name may hold spaces and parentheses
  return end_of_name != std::string::npos && end_of_name + 2 < stat.size() &&
         stat[end_of_name + 2] == 'Z';
}

// The body of the first live announcement of `address` among what `reader` holds.
std::optional<Json> take_live(dds_entity_t reader, const std::string &address) {
  void *samples[detail::kTakeBatch] = {nullptr};
  dds_sample_info_t infos[detail::kTakeBatch];
  std::optional<Json> found;
  for (;;) {
    const dds_return_t n = dds_take(reader, samples, infos, detail::kTakeBatch, detail::kTakeBatch);
    if (n <= 0)
      return found;
    for (dds_return_t i = 0; i < n && !found; ++i) {
      const auto *a = static_cast<const rsca_ctl_Announcement *>(samples[i]);
      if (!infos[i].valid_data || infos[i].instance_state != DDS_IST_ALIVE ||
          detail::str(a->address) != address || detail::str(a->kind) == protocol::kWithdrawnKind)
        continue;
      // Untrusted like any sample: a body that is no JSON object still says the address is held.
      found = detail::parse_body(a->body).value_or(Json::object());
    }
    dds_return_loan(reader, samples, n);
  }
}

// Takes what a reader holds, only so that its data-available status resets.
void forget_seen(dds_entity_t reader) {
  void *samples[detail::kTakeBatch] = {nullptr};
  dds_sample_info_t infos[detail::kTakeBatch];
  for (dds_return_t n;
       (n = dds_take(reader, samples, infos, detail::kTakeBatch, detail::kTakeBatch)) > 0;)
    dds_return_loan(reader, samples, n);
}

} // namespace

std::optional<Json> live_announcement(const dds::Participant &participant,
                                      const std::string &address, std::chrono::milliseconds wait) {
  const auto qos = detail::announcement_qos();
  const dds_entity_t pp = participant.get();
  auto topic = dds::checked(dds_create_topic(pp, &rsca_ctl_Announcement_desc,
                                             detail::kAnnouncementTopic, qos.get(), nullptr),
                            "creating the announcement topic");
  if (!topic)
    return std::nullopt; // the endpoint's own creation will say why
  auto reader = dds::checked(dds_create_reader(pp, topic->get(), qos.get(), nullptr),
                             "creating the announcement reader");
  auto peers =
      dds::checked(dds_create_reader(pp, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr),
                   "creating the participant reader");
  auto waitset = dds::checked(dds_create_waitset(pp), "creating a waitset");
  if (!reader || !peers || !waitset)
    return std::nullopt;
  dds_set_status_mask(reader->get(), DDS_DATA_AVAILABLE_STATUS | DDS_SUBSCRIPTION_MATCHED_STATUS);
  dds_set_status_mask(peers->get(), DDS_DATA_AVAILABLE_STATUS);
  dds_waitset_attach(waitset->get(), reader->get(), reader->get());
  dds_waitset_attach(waitset->get(), peers->get(), peers->get());
  DiscoveryQuiet quiet(Clock::now(), wait);
  for (auto now = Clock::now(); !quiet.over(now); now = Clock::now()) {
    const auto until = quiet.next_look();
    const dds_return_t woken =
        dds_waitset_wait(waitset->get(), nullptr, 0,
                         std::chrono::duration_cast<std::chrono::nanoseconds>(until - now).count());
    if (woken <= 0)
      continue;
    quiet.heard(Clock::now());
    forget_seen(peers->get());
    dds_subscription_matched_status_t matched;
    dds_get_subscription_matched_status(reader->get(), &matched); // resets the status
    if (auto found = take_live(reader->get(), address))
      return found;
  }
  return std::nullopt;
}

std::string own_program() {
  return program_of("self");
}

bool may_still_run(const std::string &host, std::int64_t pid, const std::string &program) {
  if (host != host_name())
    return true;
  if (pid <= 0 || pid == static_cast<std::int64_t>(::getpid()))
    return false;
  const std::string other = std::to_string(pid);
  return program_of(other) == program && !zombie(other);
}

std::optional<std::string> held_by(const dds::Participant &participant, const std::string &what,
                                   const std::string &host, std::int64_t pid,
                                   const std::string &program) {
  if (!may_still_run(host, pid, program)) {
    spdlog::info("{} was served by pid {} on this host, which runs {} no more: its last run, "
                 "taken over",
                 what, pid, program);
    return std::nullopt;
  }
  const auto &dds = participant.settings();
  return fmt::format("{} is served by pid {} on host {} (DDS domain {}, tag \"{}\")", what, pid,
                     host, dds.domain_id, dds.tag);
}

} // namespace rsca::control
