#include "allocator/plan_json.hpp"

#include <cmath>

namespace rsca::allocator {
namespace {

using nlohmann::json;

// JSON has no infinity: an unknown capacity is null.
json amount(double value) {
  return std::isfinite(value) ? json(value) : json(nullptr);
}

json amounts(const std::map<std::string, double> &values) {
  json out = json::object();
  for (const auto &[name, value] : values)
    out[name] = amount(value);
  return out;
}

json used_devices(const std::vector<UsedDevice> &used) {
  json out = json::array();
  for (const auto &u : used)
    out.push_back({{"usesdevice", u.uses_id}, {"device", u.device}, {"demand", amounts(u.demand)}});
  return out;
}

} // namespace

json to_json(const Schedule &s) {
  return {{"cpu", s.cpu},
          {"policy", to_string(s.policy)},
          {"priority", s.priority},
          {"period_ns", s.period.count()},
          {"budget_ns", s.budget.count()},
          {"deadline_ns", s.deadline.count()},
          {"response_time_ns", s.response_time.count()}};
}

json to_json(const Plan &plan) {
  json placements = json::array();
  for (const auto &p : plan.placements) {
    json entry{{"component", p.instance},
               {"device", p.device},
               {"node", p.node},
               {"implementation", p.implementation != nullptr ? p.implementation->id : ""},
               {"demand", amounts(p.demand)},
               {"uses_devices", used_devices(p.used_devices)}};
    if (p.schedule)
      entry["schedule"] = to_json(*p.schedule);
    placements.push_back(std::move(entry));
  }
  return {{"placements", placements},
          {"uses_devices", used_devices(plan.application_devices)},
          {"notes", plan.notes}};
}

json to_json(const std::vector<Rejection> &rejections) {
  json out = json::array();
  for (const auto &r : rejections)
    out.push_back({{"component", r.instance}, {"reasons", r.reasons}});
  return out;
}

json to_json(const DomainState &state) {
  json out = json::array();
  for (const auto &[id, s] : state) {
    json capacity = json::object();
    for (const auto &[name, total] : s.device.capacity) {
      auto used = s.load.allocated.find(name);
      const double allocated = used == s.load.allocated.end() ? 0.0 : used->second;
      capacity[name] = {
          {"total", amount(total)}, {"allocated", allocated}, {"free", amount(total - allocated)}};
    }
    json cpus = json::array();
    for (const auto &tasks : s.load.cpu_tasks) {
      json ids = json::array();
      for (const auto &t : tasks)
        ids.push_back(t.id);
      cpus.push_back({{"tasks", ids}, {"utilization", utilization(tasks)}});
    }
    out.push_back({{"id", id},
                   {"node", s.device.node},
                   {"kind", s.device.kind},
                   {"policy", to_string(s.device.policy)},
                   {"cpus", s.device.cpus},
                   {"capacity", capacity},
                   {"cpu_tasks", cpus}});
  }
  return out;
}

protocol::application::PlanReply
plan_reply(const tl::expected<Plan, std::vector<Rejection>> &outcome, Strategy strategy) {
  protocol::application::PlanReply reply{outcome.has_value(), std::string(to_string(strategy)),
                                         std::nullopt, std::nullopt};
  if (outcome)
    reply.plan = to_json(*outcome);
  else
    reply.rejections = to_json(outcome.error());
  return reply;
}

} // namespace rsca::allocator
