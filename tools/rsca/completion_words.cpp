#include "completion_words.hpp"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "domain_client.hpp"
#include "exit_codes.hpp"
#include "protocol/application_ops.hpp"
#include "protocol/connection_ops.hpp"
#include "protocol/domain_ops.hpp"

namespace rsca::cli {
namespace {

// Completion runs while the user waits at the keyboard.
constexpr std::chrono::milliseconds kWordsTimeout{700};

std::vector<std::string> names_of(const DomainClient &client, const std::string &kind) {
  std::vector<std::string> names;
  if (kind == "apps") {
    if (auto r = client.call<protocol::application::List>({}, kWordsTimeout))
      for (const auto &a : r->applications)
        names.push_back(a.name);
  } else if (kind == "installed") {
    if (auto r = client.call<protocol::domain::Installed>({}, kWordsTimeout))
      for (const auto &a : r->applications)
        names.push_back(a.name);
  } else if (kind == "nodes") {
    if (auto r = client.call<protocol::domain::Nodes>({}, kWordsTimeout))
      for (const auto &n : r->nodes)
        names.push_back(n.name);
  } else if (kind == "devices") {
    // As `configure` and `query` name a device: NODE:DEVICE.
    if (auto r = client.call<protocol::domain::Devices>({}, kWordsTimeout))
      for (const auto &d : r->devices) {
        const std::string id = d.value("id", ""), node = d.value("node", "");
        if (!id.empty())
          names.push_back(id.find(':') == std::string::npos && !node.empty() ? node + ":" + id
                                                                             : id);
      }
  } else if (kind == "channels") {
    if (auto r = client.call<protocol::connection::ListChannels>({}, kWordsTimeout))
      for (const auto &c : r->channels)
        names.push_back(c.name);
  }
  std::sort(names.begin(), names.end());
  return names;
}

} // namespace

void add_completion_words_command(CLI::App &completion, const GlobalOptions &global,
                                  int &exit_code) {
  auto *cmd = completion.add_subcommand(
      "words", "The live names of a kind, one a line, for a completion script");
  auto kinds = std::make_shared<std::vector<std::string>>();
  cmd->add_option("kind", *kinds, "apps, installed, nodes, devices or channels")
      ->required()
      ->check(CLI::IsMember({"apps", "installed", "nodes", "devices", "channels"}));
  cmd->callback([kinds, &global, &exit_code] {
    exit_code = kOk;
    GlobalOptions quick = global;
    quick.timeout_ms = std::min<int>(global.timeout_ms, static_cast<int>(kWordsTimeout.count()));
    auto client = DomainClient::connect(quick);
    if (!client)
      return;
    for (const auto &kind : *kinds) // one connection for all: each costs a DDS discovery
      for (const auto &name : names_of(*client, kind))
        fmt::print("{}\n", name);
  });
}

} // namespace rsca::cli
