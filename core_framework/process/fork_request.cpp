// process/fork_request.hpp: a request and a reply as "key\0value\0" pairs, and their checks.
#include "process/fork_request.hpp"

#include <charconv>
#include <limits>

#include <sched.h>

#include <fmt/format.h>

namespace rsca::process {
namespace {

void put(std::string &out, std::string_view key, std::string_view value) {
  out.append(key);
  out.push_back('\0');
  out.append(value);
  out.push_back('\0');
}

// The message's pairs; an error for a message that does not end a pair.
tl::expected<std::vector<std::pair<std::string_view, std::string_view>>, std::string>
pairs_of(std::string_view message) {
  if (message.size() > kForkMessageMax)
    return tl::unexpected(
        fmt::format("message of {} bytes, over {}", message.size(), kForkMessageMax));
  std::vector<std::pair<std::string_view, std::string_view>> pairs;
  while (!message.empty()) {
    const auto key_end = message.find('\0');
    const auto value_end =
        key_end == std::string_view::npos ? key_end : message.find('\0', key_end + 1);
    if (value_end == std::string_view::npos)
      return tl::unexpected(std::string("message ends inside a pair"));
    pairs.emplace_back(message.substr(0, key_end),
                       message.substr(key_end + 1, value_end - key_end - 1));
    message.remove_prefix(value_end + 1);
  }
  return pairs;
}

template <typename Number>
std::optional<Number> number(std::string_view text) {
  Number value{};
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error != std::errc{} || end != text.data() + text.size())
    return std::nullopt;
  return value;
}

// One pair into the request; an error names what is wrong with it.
tl::expected<void, std::string> apply(ForkRequest &request, std::string_view key,
                                      std::string_view value) {
  if (key == "program") {
    request.program = value;
  } else if (key == "arg") {
    request.args.emplace_back(value);
  } else if (key == "env") {
    const auto equals = value.find('=');
    if (equals == 0 || equals == std::string_view::npos)
      return tl::unexpected(fmt::format("environment entry \"{}\" is not NAME=value", value));
    request.env.emplace_back(value.substr(0, equals), value.substr(equals + 1));
  } else if (key == "dir") {
    request.working_dir = value;
  } else if (key == "cpu") {
    const auto cpu = number<unsigned>(value);
    if (!cpu || *cpu >= CPU_SETSIZE)
      return tl::unexpected(fmt::format("CPU \"{}\" is not a CPU number", value));
    request.cpus.push_back(*cpu);
  } else if (key == "log") {
    request.log = value == "1";
  } else if (key == "fd") {
    const auto fd = number<int>(value);
    if (!fd || *fd <= 2 || *fd >= 1024)
      return tl::unexpected(fmt::format("descriptor number \"{}\" is not above stderr", value));
    request.fd_numbers.push_back(*fd);
  } else {
    return tl::unexpected(fmt::format("unknown key \"{}\"", key));
  }
  return {};
}

} // namespace

std::string encode(const ForkRequest &request) {
  std::string out;
  if (!request.program.empty())
    put(out, "program", request.program);
  for (const auto &arg : request.args)
    put(out, "arg", arg);
  for (const auto &[name, value] : request.env)
    put(out, "env", name + "=" + value);
  if (!request.working_dir.empty())
    put(out, "dir", request.working_dir);
  for (const auto cpu : request.cpus)
    put(out, "cpu", std::to_string(cpu));
  if (request.log)
    put(out, "log", "1");
  for (const auto fd : request.fd_numbers)
    put(out, "fd", std::to_string(fd));
  return out;
}

tl::expected<ForkRequest, std::string> decode_fork_request(std::string_view message,
                                                           std::size_t fds) {
  auto pairs = pairs_of(message);
  if (!pairs)
    return tl::unexpected(pairs.error());
  ForkRequest request;
  for (const auto &[key, value] : *pairs)
    if (auto applied = apply(request, key, value); !applied)
      return tl::unexpected(applied.error());
  const std::size_t expected = request.fd_numbers.size() + (request.log ? 1 : 0);
  if (expected != fds || fds > kForkFdsMax)
    return tl::unexpected(
        fmt::format("{} descriptors came with a request that names {}", fds, expected));
  return request;
}

std::string encode(const ForkReply &reply) {
  std::string out;
  if (reply.error.empty())
    put(out, "pid", std::to_string(reply.pid));
  else
    put(out, "error", reply.error);
  return out;
}

tl::expected<ForkReply, std::string> decode_fork_reply(std::string_view message) {
  auto pairs = pairs_of(message);
  if (!pairs)
    return tl::unexpected(pairs.error());
  if (pairs->size() != 1)
    return tl::unexpected(fmt::format("a reply of {} pairs", pairs->size()));
  const auto &[key, value] = pairs->front();
  if (key == "error")
    return ForkReply{0, std::string(value)};
  const auto pid = number<pid_t>(value);
  if (key != "pid" || !pid || *pid <= 0)
    return tl::unexpected(fmt::format("a reply \"{}\" \"{}\"", key, value));
  return ForkReply{*pid, {}};
}

} // namespace rsca::process
