// The DomainManager's nodes: a node that announces itself, one that is lost, and one that is back.
//
// A node that withdraws its announcement stopped: its processes ended with it, its devices leave.
// A node whose announcement is lost with its DDS lease is lost, not dead: the domain cannot tell a
// partition from a crash. Its devices keep their reservations and take no
// new placement; its components are unreachable. When the node announces itself again the domain
// asks it which processes it runs: a component whose process lived on (the same pid, the same
// label) is reachable again in the state it had, one whose process ended is exited, and a process
// of an application released meanwhile is terminated. A node that comes back as another run (its
// pid changed) killed its processes when it died: its devices start empty.
#include <algorithm>
#include <set>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "allocator/plan_json.hpp"
#include "common/names.hpp"
#include "control/operation.hpp"
#include "domain/domain_manager_impl.hpp"

namespace rsca::domain {
namespace {

using control::Json;

Json device_ids(const protocol::node::NodeAnnouncement &node) {
  Json ids = Json::array();
  for (const auto &d : node.devices)
    ids.push_back(d.id);
  return ids;
}

std::vector<allocator::Device> devices_of(const protocol::node::NodeAnnouncement &node) {
  std::vector<allocator::Device> devices;
  for (const auto &d : node.devices)
    devices.push_back(allocator::device_from_announcement(node.node, protocol::encode(d)));
  return devices;
}

// The same run of the node daemon: its processes may have lived on.
bool same_run(const protocol::node::NodeAnnouncement &before,
              const protocol::node::NodeAnnouncement &now) {
  return before.pid == now.pid && before.host == now.host;
}

} // namespace

// A node's announcement is untrusted like any message: one that does not fit the contract is
// not taken (its devices would be guesses), and said so.
void DomainManager::Impl::node_alive(const control::AnnouncementEvent &event) {
  auto announced = protocol::decode<protocol::node::NodeAnnouncement>(event.body);
  if (!announced) {
    const std::string why = excerpt(announced.error(), 300);
    if (nodes.refused(event.address, why))
      spdlog::warn("node at {}: its announcement is not taken: {}", excerpt(event.address), why);
    return;
  }
  const std::string node = announced->node;
  const auto devices = announced->devices.size();
  end_earlier_run(event.address, *announced);
  const auto lost = nodes.take_lost(node);
  const bool restarted = lost && !same_run(lost->announcement, *announced);
  if (restarted)
    allocator.remove_node(node); // what was reserved there died with the node's last run
  allocator.set_node_devices(node, devices_of(*announced));
  const Json ids = device_ids(*announced);
  const auto pid = announced->pid;
  const bool fresh = nodes.alive(event.address, std::move(*announced));
  runtime_connections->endpoints_changed(); // connections waiting for its devices
  if (!fresh)
    return;
  if (!lost) {
    spdlog::info("node {} registered with {} device(s)", node, devices);
  } else if (restarted) {
    spdlog::warn("node {} is back as a new run (pid {}, was {}): its processes ended with the "
                 "last one",
                 node, pid, lost->announcement.pid);
  } else {
    spdlog::info("node {} is back (pid {}): finding which of its processes lived on", node, pid);
  }
  events->publish("node.added", {{"node", node}, {"devices", ids}, {"back", lost.has_value()}});
  if (lost)
    node_returns->post([this, node, epoch = node_epoch(node)] { node_back(node, epoch); });
}

// A node that restarted within its lease announces its new run while its last one is still known
// alive: no loss was seen. The last run's processes died with it (each checks that its node is
// still its parent), so that run is taken as stopped before the new one registers.
void DomainManager::Impl::end_earlier_run(const std::string &address,
                                          const protocol::node::NodeAnnouncement &now) {
  for (const auto &known : nodes.snapshot()) {
    if (known.address != address || same_run(known.announcement, now))
      continue;
    spdlog::warn("node {} restarted (pid {} on {}, was {} on {}) before its last run was seen "
                 "gone",
                 now.node, now.pid, now.host, known.announcement.pid, known.announcement.host);
    node_gone(address, /*withdrawn=*/true);
    return;
  }
}

void DomainManager::Impl::node_gone(const std::string &address, bool withdrawn) {
  {
    std::lock_guard lock(unknown_mutex);
    unknown.erase(address); // an unknown component that went away
  }
  auto gone = nodes.gone(address, /*lost=*/!withdrawn);
  if (!gone)
    return;
  const std::string node = gone->announcement.node;
  if (withdrawn)
    spdlog::warn("node {} stopped; its devices leave the domain", node);
  else
    spdlog::warn("node {} is lost: its devices take no new placement and its components are "
                 "unreachable until it is back",
                 node);
  events->publish("node.removed", {{"node", node},
                                   {"devices", device_ids(gone->announcement)},
                                   {"why", withdrawn ? "stopped" : "lost"}});
  if (withdrawn)
    allocator.remove_node(node);
  else
    allocator.suspend_node(node);
  const auto why = fmt::format("its node {} {}", node, withdrawn ? "stopped" : "is lost");
  // A launch waiting on one of them fails now, and calls to them end.
  for (const auto &component : components.node_gone(node, why))
    endpoint->abandon(component, why);
  // A node that stops ends its processes first: what is left ended with it.
  if (withdrawn) {
    mark_exited([&node](const ComponentInstance &c) { return c.node == node; }, why);
    std::lock_guard lock(lost_mutex);
    lost_processes.erase(node);
  } else
    mark_unreachable(node, why);
  runtime_connections->owner_gone_later([prefix = node + ":"](const PortRef &ref) {
    return ref.kind == PortRef::Kind::Device && ref.owner.starts_with(prefix);
  });
}

void DomainManager::Impl::mark_unreachable(const std::string &node, const std::string &why) {
  std::lock_guard lock(lost_mutex);
  ++node_epochs[node]; // a node_back under way for an earlier return no longer applies
  auto &processes = lost_processes[node];
  applications.update_all([&](Application &app) {
    for (auto &c : app.components) {
      if (c.node != node || c.pid == 0 || c.state == ComponentState::Exited ||
          c.state == ComponentState::Unreachable)
        continue;
      c.state_before_lost = c.state;
      c.state = ComponentState::Unreachable;
      processes.push_back({c.pid, fmt::format("{}/{}", app.name, c.id)});
      spdlog::warn("component {} of application {} is unreachable: {}; the application is "
                   "degraded",
                   c.id, app.name, why);
      events->publish(
          "component.unreachable",
          {{"application", app.name}, {"component", c.id}, {"node", node}, {"why", why}});
    }
  });
}

// A process a release could not have ended (its node lost, or not answering) joins those its
// node's return ends (node_back). Kept also for a node not yet seen lost: its loss may be
// noticed only after the call failed; a node that stops drops the list (node_gone).
void DomainManager::Impl::end_when_back(const std::string &node, long pid,
                                        const std::string &label) {
  std::lock_guard lock(lost_mutex);
  auto &processes = lost_processes[node];
  // An application released while its node is lost: its processes were listed at the loss.
  if (std::none_of(processes.begin(), processes.end(),
                   [pid](const LostProcess &p) { return p.pid == pid; }))
    processes.push_back({pid, label});
}

std::uint64_t DomainManager::Impl::node_epoch(const std::string &node) {
  std::lock_guard lock(lost_mutex);
  return node_epochs[node];
}

// The processes node `node` runs (pids: unique on one run of a node), asked a few times: right
// after the node is back, the way to it may not be matched yet. Nothing when it is lost again,
// the domain stops, or it does not answer.
std::optional<std::set<long>> DomainManager::Impl::processes_on(const std::string &node,
                                                                std::uint64_t epoch) {
  constexpr int kAttempts = 5;
  for (int attempt = 1; attempt <= kAttempts; ++attempt) {
    const auto address = nodes.address_of(node);
    if (!address || stopping_node_returns.load() || node_epoch(node) != epoch)
      return std::nullopt;
    auto status = control::call<protocol::node::Status>(*endpoint, *address, {},
                                                        std::chrono::milliseconds(1000));
    if (status) {
      std::set<long> pids;
      for (const auto &p : status->processes)
        pids.insert(static_cast<long>(p.pid));
      return pids;
    }
    spdlog::warn("node {} is back but does not say what it runs ({}; attempt {} of {})", node,
                 status.error().message, attempt, kAttempts);
  }
  return std::nullopt;
}

// Runs on its own thread (node_returns): it waits for the node's answer. `epoch`: the node's
// when it came back; if it is lost again meanwhile, this return is over and changes nothing.
void DomainManager::Impl::node_back(const std::string &node, std::uint64_t epoch) {
  const auto running = processes_on(node, epoch);
  std::vector<LostProcess> lost;
  {
    std::lock_guard lock(lost_mutex);
    if (node_epochs[node] != epoch || !nodes.address_of(node) || stopping_node_returns.load())
      return; // its processes stay unreachable, to be settled at its next return
    auto it = lost_processes.find(node);
    if (it == lost_processes.end())
      return;
    lost = std::move(it->second);
    lost_processes.erase(it);
    // One pass under lost_mutex: a loss meanwhile (mark_unreachable) waits for it.
    std::set<long> claimed;
    applications.update_all([&](Application &app) {
      for (auto &c : app.components) {
        if (c.node != node || c.state != ComponentState::Unreachable)
          continue;
        claimed.insert(c.pid);
        if (!running || running->count(c.pid) == 0)
          continue; // marked exited below, as every other exit
        c.state = c.state_before_lost;
        components.reachable_again(c.address);
        spdlog::info("component {} of application {} is reachable again (pid {})", c.id, app.name,
                     c.pid);
        events->publish("component.reachable",
                        {{"application", app.name}, {"component", c.id}, {"node", node}});
      }
    });
    mark_exited(
        [&](const ComponentInstance &c) {
          return c.node == node && c.state == ComponentState::Unreachable;
        },
        fmt::format("it ended while its node {} was lost", node));
    std::erase_if(lost, [&](const LostProcess &p) {
      return claimed.count(p.pid) != 0 || !running || running->count(p.pid) == 0;
    });
  }
  // A process of an application released, or of a launch rolled back, while its node was lost
  // runs for nobody: ended.
  const auto address = nodes.address_of(node);
  for (const auto &p : lost) {
    if (!address)
      break;
    spdlog::info("node {}: ending {} (pid {}): it runs for nobody (its application was released, "
                 "or its launch rolled back, while the node was lost)",
                 node, p.label, p.pid);
    auto ended = control::call<protocol::node::Terminate>(*endpoint, *address, {p.pid},
                                                          options.call_timeout);
    if (!ended)
      spdlog::warn("node {}: {} (pid {}) not ended: {}", node, p.label, p.pid,
                   ended.error().message);
  }
}

} // namespace rsca::domain
