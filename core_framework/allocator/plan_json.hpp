// Plans, schedules and rejections as JSON: what `rsca plan --json` prints, what the domain
// answers to app.plan, and how a running application shows its components' schedules.
#pragma once

#include <vector>

#include <nlohmann/json.hpp>

#include "allocator/planner.hpp"
#include "protocol/application_ops.hpp"

namespace rsca::allocator {

nlohmann::json to_json(const Schedule &schedule);
nlohmann::json to_json(const Plan &plan);
nlohmann::json to_json(const std::vector<Rejection> &rejections);
// The state of every device: capacities total, allocated and free; tasks per CPU.
nlohmann::json to_json(const DomainState &state);
// A plan's outcome as app.plan answers it (and `rsca plan --node` prints it): the plan when
// admitted, else the rejections.
protocol::application::PlanReply
plan_reply(const tl::expected<Plan, std::vector<Rejection>> &outcome, Strategy strategy);

} // namespace rsca::allocator
