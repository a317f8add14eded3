// The planner's search: a depth-first search over the components, most constrained first (a
// host-collocation group together), trying each one's candidates (device x implementation) in
// the strategy's order against the rules of planner_rules.cpp, backtracking on failure, within
// a budget of tries. It works on a copy of the domain state and remembers the first reasons it
// met, so a rejection can say per component and device why nothing fits.
#include "allocator/planner_impl.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>

#include <fmt/format.h>

namespace rsca::allocator::detail {
namespace {

// An affinity this heavy (about 9 Mbps and more) keeps its pair on one host even when spreading.
constexpr double kHeavyAffinity = 10.0;

// ---- the search ---------------------------------------------------------------------------------

struct Candidate {
  std::string device;
  DeviceState *state = nullptr; // in the search's working copy, whose nodes never move
  const ResolvedImplementation *implementation = nullptr;
};

// One way to place a component, with what it changes in the state.
struct Step {
  Placement placement;
  std::size_t task_index = 0; // where its task stands in its CPU's task set
};

using Reservations = std::map<std::string, std::map<std::string, double>>; // device -> demand

class Search {
public:
  Search(const DomainState &state, const PlanRequest &request, const PlanOptions &options)
      : state_(state), request_(request), options_(options) {}

  tl::expected<Plan, std::vector<Rejection>> run() {
    if (auto unplaceable = find_candidates(); !unplaceable.empty())
      return tl::unexpected(std::move(unplaceable));
    order_components();
    index_collocations();
    index_affinities();
    fair_share_ = fair_share();
    steps_.resize(order_.size());
    if (place(0))
      return finish();
    return tl::unexpected(explain());
  }

private:
  // Static candidates per component; the components that have none, with every reason.
  std::vector<Rejection> find_candidates() {
    std::vector<Rejection> rejections;
    candidates_.resize(request_.components.size());
    first_reasons_.resize(request_.components.size());
    for (std::size_t i = 0; i < request_.components.size(); ++i) {
      const auto &c = request_.components[i];
      Rejection rejection{c.instance, {}};
      if (auto why = unrunnable(*c.softpkg)) {
        rejection.reasons.push_back(*why);
        rejections.push_back(std::move(rejection));
        continue;
      }
      for (const auto &impl : c.softpkg->implementations)
        for (auto &[id, s] : working_) {
          if (s.device.kind != "gpp" || (c.device && *c.device != id))
            continue;
          auto why = implementation_mismatch(*impl.implementation, s.device);
          if (!why)
            why = dependency_mismatch(impl, s.device);
          if (!why)
            why = requires_mismatch(c, s.device);
          if (why)
            rejection.reasons.push_back(
                fmt::format("{} ({}): {}", id, impl.implementation->id, *why));
          else
            candidates_[i].push_back({id, &s, &impl});
        }
      first_reasons_[i] = rejection.reasons;
      if (!candidates_[i].empty())
        continue;
      if (rejection.reasons.empty())
        rejection.reasons.push_back(
            c.device ? fmt::format("the assigned device {} is not in the domain", *c.device)
                     : "no device that runs components is in the domain");
      rejections.push_back(std::move(rejection));
    }
    return rejections;
  }

  // Why nothing of a package can run anywhere: a file it names is missing, or it has no
  // implementation.
  static std::optional<std::string> unrunnable(const profile::ResolvedSoftPkg &pkg) {
    if (!pkg.unavailable.empty())
      return fmt::format("its package cannot run: {}", pkg.unavailable.front().message);
    if (pkg.implementations.empty())
      return std::string("its package has no implementation");
    return std::nullopt;
  }

  // Fewest candidates first; a collocation group's members next to each other.
  void order_components() {
    // A group sorts by its most constrained member, so that its members stay together.
    std::map<std::string, std::size_t> group_candidates;
    for (std::size_t i = 0; i < request_.components.size(); ++i) {
      const auto &group = request_.components[i].collocation;
      if (group.empty())
        continue;
      auto [it, fresh] = group_candidates.emplace(group, candidates_[i].size());
      if (!fresh)
        it->second = std::min(it->second, candidates_[i].size());
    }
    std::vector<std::tuple<std::size_t, std::string, std::size_t>> keyed;
    for (std::size_t i = 0; i < request_.components.size(); ++i) {
      const auto &group = request_.components[i].collocation;
      keyed.emplace_back(group.empty() ? candidates_[i].size() : group_candidates[group], group, i);
    }
    std::sort(keyed.begin(), keyed.end());
    order_.clear();
    for (const auto &[n, group, i] : keyed)
      order_.push_back(i);
  }

  // Each collocation's size and what it asks of its host as a whole.
  void index_collocations() {
    for (const auto &c : request_.components)
      if (!c.collocation.empty())
        ++group_size_[c.collocation];
    for (const auto &g : request_.collocations)
      group_request_[g.id] = &g;
  }

  // The CPU a collocation's last member is charged on top of its own demand, so that the group
  // is charged its reservation at least; 0 for any other member.
  double reservation_top_up(const ComponentRequest &c, double own_cpu) const {
    const auto request = group_request_.find(c.collocation);
    if (c.collocation.empty() || request == group_request_.end())
      return 0;
    const auto placed = group_placed_.find(c.collocation);
    const std::size_t before = placed == group_placed_.end() ? 0 : placed->second.count;
    if (before + 1 < group_size_.at(c.collocation))
      return 0;
    const double charged = (placed == group_placed_.end() ? 0.0 : placed->second.cpu) + own_cpu;
    return std::max(0.0, request->second->cpu_reservation - charged);
  }

  // Each component's partners (affinities both ways), so that ranking costs its degree only.
  void index_affinities() {
    for (const auto &a : request_.affinities) {
      partners_[a.a].emplace_back(a.b, a.weight);
      partners_[a.b].emplace_back(a.a, a.weight);
    }
  }

  // How many of the application's components a device takes when spreading: the components
  // divided evenly among the devices that could take any of them.
  std::size_t fair_share() const {
    std::set<std::string> devices;
    for (const auto &list : candidates_)
      for (const auto &candidate : list)
        devices.insert(candidate.device);
    const std::size_t n = request_.components.size();
    return devices.empty() ? n : (n + devices.size() - 1) / devices.size();
  }

  // The weight of `instance`'s placed partners per node they are on.
  std::map<std::string, double> affinity_by_node(const std::string &instance,
                                                 bool heavy_only) const {
    std::map<std::string, double> out;
    auto partners = partners_.find(instance);
    if (partners == partners_.end())
      return out;
    for (const auto &[other, weight] : partners->second) {
      if (heavy_only && weight < kHeavyAffinity)
        continue;
      if (auto it = node_of_.find(other); it != node_of_.end())
        out[it->second] += weight;
    }
    return out;
  }

  // The candidates of component `i` in the order the strategy prefers them.
  // Both strategies prefer the node of placed partners (connections: the data stays in one host,
  // and in one component host when both are shared libraries). Spreading, a device is preferred
  // so only until it has its fair share of the application, unless the pair is heavy.
  std::vector<Candidate> ranked(std::size_t i) const {
    const auto &c = request_.components[i];
    const bool pack = options_.strategy == Strategy::Pack;
    std::vector<std::tuple<double, double, std::size_t>> keyed;
    const auto &list = candidates_[i];
    const auto affinity = affinity_by_node(c.instance, /*heavy_only=*/false);
    const auto heavy = pack ? affinity : affinity_by_node(c.instance, /*heavy_only=*/true);
    for (std::size_t k = 0; k < list.size(); ++k) {
      const auto &s = *list[k].state;
      auto placed = placed_on_.find(list[k].device);
      const bool full = !pack && placed != placed_on_.end() && placed->second >= fair_share_;
      const auto &weights = full ? heavy : affinity;
      auto a = weights.find(s.device.node);
      const double load = load_of(s);
      keyed.emplace_back(a == weights.end() ? 0.0 : -a->second, pack ? -load : load, k);
    }
    std::stable_sort(keyed.begin(), keyed.end());
    std::vector<Candidate> out;
    out.reserve(keyed.size());
    for (const auto &[a, l, k] : keyed)
      out.push_back(list[k]);
    return out;
  }

  // The step that places component `i` on the candidate, or why it does not fit now.
  static bool uses_any_device(const ComponentRequest &c) {
    if (c.softpkg == nullptr)
      return false;
    if (c.softpkg->spd && !c.softpkg->spd->uses_devices.empty())
      return true;
    return std::any_of(
        c.softpkg->implementations.begin(), c.softpkg->implementations.end(), [](const auto &impl) {
          return impl.implementation != nullptr && !impl.implementation->uses_devices.empty();
        });
  }

  // The step that places component `i` on the candidate, or why it does not fit now. The devices
  // it uses are looked for on the candidate's node, or anywhere with `remote_devices`.
  tl::expected<Step, std::string> try_candidate(std::size_t i, const Candidate &candidate,
                                                bool remote_devices) const {
    const auto &c = request_.components[i];
    const auto &s = *candidate.state;
    const auto &impl = *candidate.implementation->implementation;
    if (!c.collocation.empty())
      if (auto it = group_node_.find(c.collocation);
          it != group_node_.end() && it->second != s.device.node)
        return tl::unexpected(
            fmt::format("hostcollocation {} is on node {}", c.collocation, it->second));
    if (auto why = missing_referenced_device(c, s.device.node))
      return tl::unexpected(*why);
    Step step{{c.instance,
               candidate.device,
               s.device.node,
               &impl,
               demand_of(impl, c.timing),
               task_of(c.instance, impl, c.timing),
               std::nullopt,
               {}}};
    auto &cpu = step.placement.demand[kCpuCapacity];
    if (const double top_up = reservation_top_up(c, cpu); top_up > 0) {
      cpu += top_up;
      if (auto why = capacity_shortfall(step.placement.demand, s))
        return tl::unexpected(
            fmt::format("hostcollocation {} reserves {:.4g} cores: {}", c.collocation,
                        group_request_.at(c.collocation)->cpu_reservation / 100, *why));
    }
    if (cpu == 0)
      step.placement.demand.erase(kCpuCapacity);
    if (auto why = capacity_shortfall(step.placement.demand, s))
      return tl::unexpected(*why);
    if (const auto &task = step.placement.task) {
      auto admitted = admit(*task, s, options_.strategy);
      if (!admitted)
        return tl::unexpected(admitted.error());
      step.placement.schedule =
          schedule_of(*task, admitted->first, admitted->second, s.device.policy);
    }
    // What this step reserves so far: its own usesdevice entries must not count a device twice.
    Reservations pending{{candidate.device, step.placement.demand}};
    // The softpkg's usesdevice apply to every implementation; the implementation adds its own.
    std::vector<const profile::UsesDevice *> all_uses;
    if (c.softpkg != nullptr && c.softpkg->spd)
      for (const auto &uses : c.softpkg->spd->uses_devices)
        all_uses.push_back(&uses);
    for (const auto &uses : impl.uses_devices)
      all_uses.push_back(&uses);
    for (const auto *uses_ptr : all_uses) {
      const auto &uses = *uses_ptr;
      auto used = find_used_device(uses, remote_devices ? "" : s.device.node, pending);
      if (!used)
        return tl::unexpected(used.error());
      add(pending[used->device], used->demand, +1);
      step.placement.used_devices.push_back(std::move(*used));
    }
    return step;
  }

  // A device on `node` (any node when empty) that satisfies `uses`, with its demand.
  // `pending`: reserved by the caller but not yet applied to the working state.
  tl::expected<UsedDevice, std::string> find_used_device(const profile::UsesDevice &uses,
                                                         const std::string &node,
                                                         const Reservations &pending) const {
    std::string first_reason;
    for (const auto &[id, s] : working_) {
      if (!node.empty() && s.device.node != node)
        continue;
      auto reserved = pending.find(id);
      std::optional<DeviceState> with_pending;
      if (reserved != pending.end()) {
        with_pending = s;
        add(with_pending->load.allocated, reserved->second, +1);
      }
      auto why = uses_mismatch(uses, with_pending ? *with_pending : s);
      if (!why)
        return UsedDevice{uses.id, id, uses_demand(uses, s.device)};
      if (first_reason.empty())
        first_reason = fmt::format("{}: {}", id, *why);
    }
    return tl::unexpected(
        fmt::format("usesdevice {}: no device {}{}", uses.id,
                    node.empty() ? "in the domain fits" : "on node " + node + " fits",
                    first_reason.empty() ? "" : " (" + first_reason + ")"));
  }

  void apply(Step &step, double sign) {
    auto &s = working_.at(step.placement.device);
    add(s.load.allocated, step.placement.demand, sign);
    for (const auto &used : step.placement.used_devices)
      add(working_.at(used.device).load.allocated, used.demand, sign);
    if (step.placement.task && step.placement.schedule) {
      const unsigned cpu = step.placement.schedule->cpu;
      if (s.load.cpu_tasks.size() <= cpu)
        s.load.cpu_tasks.resize(cpu + 1);
      auto &tasks = s.load.cpu_tasks[cpu];
      if (sign > 0) {
        step.task_index = tasks.size();
        tasks.push_back(*step.placement.task);
      } else {
        tasks.pop_back(); // steps are undone in reverse order
      }
    }
  }

  bool place(std::size_t k) {
    if (k == order_.size())
      return complete();
    const std::size_t i = order_[k];
    const auto &c = request_.components[i];
    bool any_fit = false;
    std::vector<std::string> reasons;
    const auto candidates = ranked(i);
    // A component prefers the nodes of the devices it uses; only when no candidate has them at
    // hand does it use them across the network (their ports are DDS connections either way).
    const int passes = uses_any_device(c) ? 2 : 1;
    for (int pass = 0; pass < passes; ++pass) {
      reasons.clear(); // the broadest attempt explains a rejection
      for (const auto &candidate : candidates) {
        if (++tries_ > options_.budget) {
          budget_exhausted_ = true;
          return false;
        }
        auto step = try_candidate(i, candidate, /*remote_devices=*/pass == 1);
        if (!step) {
          reasons.push_back(fmt::format("{} ({}): {}", candidate.device,
                                        candidate.implementation->implementation->id,
                                        step.error()));
          continue;
        }
        any_fit = true;
        const bool opens_group = !c.collocation.empty() && group_node_.count(c.collocation) == 0;
        if (opens_group)
          group_node_[c.collocation] = step->placement.node;
        count_in_group(c, step->placement, +1);
        node_of_[c.instance] = step->placement.node;
        ++placed_on_[step->placement.device];
        apply(*step, +1);
        steps_[k] = std::move(*step);
        if (place(k + 1))
          return true;
        apply(steps_[k], -1);
        node_of_.erase(c.instance);
        --placed_on_[steps_[k].placement.device];
        count_in_group(c, steps_[k].placement, -1);
        if (opens_group)
          group_node_.erase(c.collocation);
        if (budget_exhausted_)
          return false;
      }
    }
    if (!any_fit && blocked_ == nullptr_index) {
      blocked_ = i;
      blocked_reasons_ = std::move(reasons);
      blocked_reasons_.insert(blocked_reasons_.end(), first_reasons_[i].begin(),
                              first_reasons_[i].end());
    }
    return false;
  }

  void count_in_group(const ComponentRequest &c, const Placement &p, int sign) {
    if (c.collocation.empty())
      return;
    auto &placed = group_placed_[c.collocation];
    placed.count = static_cast<std::size_t>(static_cast<long>(placed.count) + sign);
    const auto cpu = p.demand.find(kCpuCapacity);
    placed.cpu += sign * (cpu == p.demand.end() ? 0.0 : cpu->second);
  }

  // A collocation that refers to the application's usesdevice (usesdeviceref) goes only to a node
  // that has such a device: checked as each member is tried, so that a wrong node is left at
  // once rather than after everything else is placed. Capacity is checked when all are.
  std::optional<std::string> missing_referenced_device(const ComponentRequest &c,
                                                       const std::string &node) const {
    const auto request = group_request_.find(c.collocation);
    if (c.collocation.empty() || request == group_request_.end())
      return std::nullopt;
    for (const auto &id : request->second->uses_devices) {
      const auto uses = std::find_if(request_.uses_devices.begin(), request_.uses_devices.end(),
                                     [&](const profile::UsesDevice &u) { return u.id == id; });
      if (uses == request_.uses_devices.end())
        continue;
      if (auto found = find_used_device(*uses, node, {}); !found)
        return fmt::format("hostcollocation {} goes next to usesdevice {}: {}", c.collocation, id,
                           found.error());
    }
    return std::nullopt;
  }

  // Where the SAD's usesdevice `id` must be found: the node of a collocation that refers to it
  // (usesdeviceref), "" for anywhere; nullopt when two such collocations are on different nodes.
  std::optional<std::string> node_for_uses(const std::string &id) const {
    std::string node;
    for (const auto &g : request_.collocations) {
      if (std::find(g.uses_devices.begin(), g.uses_devices.end(), id) == g.uses_devices.end())
        continue;
      const auto it = group_node_.find(g.id);
      if (it == group_node_.end())
        continue;
      if (!node.empty() && node != it->second)
        return std::nullopt;
      node = it->second;
    }
    return node;
  }

  // Every component is placed: the SAD's own usesdevice and the latency bounds decide.
  bool complete() {
    Reservations pending;
    std::vector<UsedDevice> used_devices;
    for (const auto &uses : request_.uses_devices) {
      const auto node = node_for_uses(uses.id);
      if (!node) {
        leaf_failure_ = fmt::format("usesdevice {}: host collocations that use its device are "
                                    "on different nodes",
                                    uses.id);
        return false;
      }
      auto used = find_used_device(uses, *node, pending);
      if (!used) {
        leaf_failure_ = used.error();
        return false;
      }
      add(pending[used->device], used->demand, +1);
      used_devices.push_back(std::move(*used));
    }
    refresh_schedules();
    if (auto why = latency_violation()) {
      leaf_failure_ = *why;
      return false;
    }
    application_devices_ = std::move(used_devices);
    return true;
  }

  // A task placed later can change the priority (deadline monotonic) and the response time of
  // the tasks already on its CPU: every schedule of this plan is read off its CPU's final set.
  void refresh_schedules() {
    std::map<std::pair<const DeviceState *, unsigned>, Schedulability> verdicts;
    for (auto &step : steps_) {
      auto &schedule = step.placement.schedule;
      if (!schedule)
        continue;
      const auto &s = working_.at(step.placement.device);
      auto [it, fresh] = verdicts.try_emplace({&s, schedule->cpu});
      if (fresh)
        it->second = analyse(s.load.cpu_tasks[schedule->cpu], s.device.policy);
      const auto &verdict = it->second.tasks[step.task_index];
      schedule->priority = verdict.priority;
      schedule->response_time = verdict.response_time;
    }
  }

  // A latency path whose worst case exceeds its bound: the first component's response time,
  // then per hop the receiver's period (it samples its input once a period) and response time.
  std::optional<std::string> latency_violation() const {
    for (const auto &path : request_.latency_paths) {
      Nanos worst{0};
      for (std::size_t n = 0; n < path.components.size(); ++n) {
        const Schedule *s = schedule_of_instance(path.components[n]);
        if (s == nullptr)
          continue;
        worst += s->response_time + (n > 0 ? s->period : Nanos{0});
      }
      if (!path.bound.infinite() && worst > nanos_of(path.bound))
        return fmt::format("latency path {}: worst case {} exceeds its bound {}", path.id,
                           format_duration(worst), format_duration(nanos_of(path.bound)));
    }
    return std::nullopt;
  }

  const Schedule *schedule_of_instance(const std::string &instance) const {
    for (const auto &step : steps_)
      if (step.placement.instance == instance && step.placement.schedule)
        return &*step.placement.schedule;
    return nullptr;
  }

  static std::string format_duration(Nanos d) { return rsca::format_duration(Duration{d}); }

  Plan finish() const {
    Plan plan;
    std::vector<Placement> by_request(request_.components.size());
    for (std::size_t k = 0; k < order_.size(); ++k)
      by_request[order_[k]] = steps_[k].placement;
    plan.placements = std::move(by_request);
    plan.application_devices = application_devices_;
    std::set<std::string> unknown;
    for (const auto &p : plan.placements)
      for (const auto &[name, total] : state_.at(p.device).device.capacity)
        if (!std::isfinite(total))
          unknown.insert(fmt::format("{} of {}", name, p.device));
    for (const auto &u : unknown)
      plan.notes.push_back(fmt::format("{} is not known: not checked", u));
    return plan;
  }

  std::vector<Rejection> explain() const {
    std::vector<Rejection> out;
    if (blocked_ != nullptr_index)
      out.push_back({request_.components[blocked_].instance, blocked_reasons_});
    if (!leaf_failure_.empty())
      out.push_back({"(application)", {leaf_failure_}});
    if (budget_exhausted_)
      out.push_back({"(search)",
                     {fmt::format("no plan found within {} placements tried; the domain may still "
                                  "fit the application in a way not searched",
                                  options_.budget)}});
    if (out.empty())
      out.push_back({"(application)", {"no placement satisfies every constraint together"}});
    return out;
  }

  static constexpr std::size_t nullptr_index = static_cast<std::size_t>(-1);

  const DomainState &state_;
  const PlanRequest &request_;
  const PlanOptions &options_;
  DomainState working_ = state_;
  std::vector<std::vector<Candidate>> candidates_;
  std::vector<std::vector<std::string>> first_reasons_; // static reasons, per component
  std::vector<std::size_t> order_;
  std::vector<Step> steps_; // by search position
  std::map<std::string, std::vector<std::pair<std::string, double>>> partners_;
  std::map<std::string, std::string> node_of_;   // placed instance -> node
  std::map<std::string, std::size_t> placed_on_; // device -> components of this plan on it
  std::size_t fair_share_ = 0;
  std::map<std::string, std::string> group_node_; // hostcollocation -> node
  std::map<std::string, std::size_t> group_size_; // hostcollocation -> its components
  std::map<std::string, const CollocationRequest *> group_request_;
  struct GroupPlaced {
    std::size_t count = 0;
    double cpu = 0; // cpu_capacity charged to its members so far
  };
  std::map<std::string, GroupPlaced> group_placed_;
  std::vector<UsedDevice> application_devices_;
  std::size_t tries_ = 0;
  bool budget_exhausted_ = false;
  std::size_t blocked_ = nullptr_index;
  std::vector<std::string> blocked_reasons_;
  std::string leaf_failure_;
};

} // namespace

tl::expected<Plan, std::vector<Rejection>>
search(const DomainState &state, const PlanRequest &request, const PlanOptions &options) {
  return Search(state, request, options).run();
}

} // namespace rsca::allocator::detail
