#include "protocol/status.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "protocol/json_text.hpp"

namespace rsca::protocol {

std::string_view to_string(Status status) {
  switch (status) {
  case Status::Ok:
    return "ok";
  case Status::BadRequest:
    return "bad request";
  case Status::NotFound:
    return "not found";
  case Status::Failed:
    return "failed";
  case Status::Timeout:
    return "timeout";
  case Status::Unavailable:
    return "unavailable";
  case Status::Rejected:
    return "rejected";
  }
  return "unknown";
}

bool is_known(std::int32_t status) {
  return status >= static_cast<std::int32_t>(Status::Ok) &&
         status <= static_cast<std::int32_t>(Status::Rejected);
}

namespace {

std::string detail_of(const Diagnostic &d) {
  if (d.where.file.empty())
    return fmt::format("{}: {}", d.rule, d.message);
  return to_string(d);
}

} // namespace

tl::unexpected<CallError> call_error(Status status, const Error &findings) {
  const auto &all = findings.diagnostics();
  if (all.empty())
    return call_error(status, "failed, with no finding given");
  CallError error{status, all.front().message};
  if (all.size() > 1)
    error.message += fmt::format(" (and {} more)", all.size() - 1);
  for (const auto &d : all)
    error.details.push_back(detail_of(d));
  return tl::unexpected(std::move(error));
}

nlohmann::json error_body_json(const CallError &error) {
  auto body = nlohmann::json::object();
  if (!error.details.empty())
    body["details"] = error.details;
  if (error.maybe_received)
    body["maybe_received"] = true;
  return body;
}

std::string error_body(const CallError &error) {
  if (error.details.empty() && !error.maybe_received)
    return {};
  return error_body_json(error).dump();
}

bool maybe_received_of(const nlohmann::json &body) {
  return body.is_object() && body.value("maybe_received", false) == true;
}

std::vector<std::string> details_of_text(std::string_view body) {
  if (body.empty())
    return {};
  return details_of(parse_json(body).value_or(nlohmann::json()));
}

// Bounded: the reply is untrusted.
std::vector<std::string> details_of(const nlohmann::json &json) {
  if (!json.is_object() || !json.contains("details") || !json.at("details").is_array())
    return {};
  std::vector<std::string> details;
  for (const auto &d : json.at("details"))
    if (d.is_string() && details.size() < 1000)
      details.push_back(d.get<std::string>());
  return details;
}

} // namespace rsca::protocol
