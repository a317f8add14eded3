// tools/rsca/app_graph.hpp: the clusters (node, then device), the components and devices in them,
// the channels, the external ports, and the edges between them. Nodes of the graph get ids of
// their own (c0, d1, ch2, x3), never a name: a name is only ever a label, escaped.
#include "app_graph.hpp"

#include <map>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "common/units.hpp"

namespace rsca::cli {
namespace {

namespace app_ops = protocol::application;
using protocol::Json;
using protocol::connection::ConnectionState;
using protocol::connection::PortEnd;

// The length of the UTF-8 sequence at `at`; 0 when none starts there.
std::size_t utf8_length(std::string_view s, std::size_t at) {
  const auto lead = static_cast<unsigned char>(s[at]);
  std::size_t n = 0;
  if (lead < 0x80)
    n = 1;
  else if ((lead >> 5) == 0x6)
    n = 2;
  else if ((lead >> 4) == 0xE)
    n = 3;
  else if ((lead >> 3) == 0x1E)
    n = 4;
  if (n == 0 || at + n > s.size())
    return 0;
  for (std::size_t i = 1; i < n; ++i)
    if ((static_cast<unsigned char>(s[at + i]) & 0xC0) != 0x80)
      return 0;
  return n;
}

// One character of ASCII as DOT text.
void append_ascii(std::string &out, char c) {
  if (c == '"' || c == '\\') {
    out += '\\';
    out += c;
  } else if (c == '\n') {
    out += "\\n";
  } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
    out += '?';
  } else {
    out += c;
  }
}

// Lines joined by DOT's line break, each escaped.
std::string dot_lines(const std::vector<std::string> &lines) {
  return dot_string(fmt::format("{}", fmt::join(lines, "\n")));
}

// Where a device's owner runs: the node in its id (NODE:DEVICE).
std::string node_of_device(const std::string &device) {
  const auto colon = device.find(':');
  return colon == std::string::npos ? std::string() : device.substr(0, colon);
}

std::string_view component_colour(app_ops::ComponentState state) {
  using S = app_ops::ComponentState;
  switch (state) {
  case S::Running:
    return "palegreen";
  case S::Exited:
    return "lightcoral";
  case S::Unreachable:
    return "lightgrey";
  default:
    return "lightyellow";
  }
}

// How an edge shows its connection's state: a colour and a style that also tell it apart in
// black and white.
struct EdgeLook {
  std::string_view word;
  std::string_view colour;
  std::string_view style;
};

EdgeLook look_of(const std::optional<ConnectionState> &state) {
  if (!state)
    return {"unknown", "grey50", "dotted"};
  switch (*state) {
  case ConnectionState::Connected:
    return {"connected", "darkgreen", "solid"};
  case ConnectionState::Pending:
    return {"pending", "darkorange", "dashed"};
  case ConnectionState::Failed:
    return {"failed", "red", "bold"};
  }
  return {"unknown", "grey50", "dotted"};
}

std::string text_of(const Json &qos, const char *key) {
  const auto it = qos.find(key);
  return it != qos.end() && it->is_string() ? it->get<std::string>() : std::string();
}

// A count or a duration in ns; none when absent, negative or not a number ("infinite").
std::optional<std::int64_t> count_of(const Json &qos, const char *key) {
  const auto it = qos.find(key);
  if (it == qos.end() || !it->is_number_integer() || it->get<std::int64_t>() < 0)
    return std::nullopt;
  return it->get<std::int64_t>();
}

// The QoS that decides whether and how data arrives: reliability, history (with its depth),
// deadline (none when infinite), from dds/port_qos.hpp's JSON form.
std::string qos_text(const Json &qos) {
  if (!qos.is_object())
    return {};
  std::vector<std::string> parts;
  if (auto reliability = text_of(qos, "reliability"); !reliability.empty())
    parts.push_back(reliability);
  const auto depth = count_of(qos, "depth");
  if (auto history = text_of(qos, "history"); !history.empty())
    parts.push_back(depth ? fmt::format("{}({})", history, *depth) : history);
  if (const auto deadline = count_of(qos, "deadline_ns"))
    parts.push_back("deadline " + format_duration(Duration{std::chrono::nanoseconds(*deadline)}));
  return fmt::format("{}", fmt::join(parts, ", "));
}

// The graph being written: its ids for the application's parts, and its text.
class Graph {
public:
  explicit Graph(const app_ops::ApplicationView &app) : app_(app) {}

  std::string write() {
    collect_devices();
    out_ += fmt::format("digraph {} {{\n", dot_string(app_.name));
    out_ +=
        fmt::format("  graph [label={}, labelloc=t, rankdir=LR, fontname=Helvetica];\n",
                    dot_string(fmt::format("{} ({}): {}", app_.name, app_.installed, app_.state)));
    out_ += "  node [fontname=Helvetica, fontsize=11];\n"
            "  edge [fontname=Helvetica, fontsize=9];\n";
    write_clusters();
    for (const auto &c : app_.connections)
      write_connection(c);
    for (std::size_t i = 0; i < app_.external_ports.size(); ++i)
      write_external_port(app_.external_ports[i], i);
    out_ += "}\n";
    return std::move(out_);
  }

private:
  // Every device a component runs on or a connection reaches, by node: the clusters.
  void collect_devices() {
    for (const auto &c : app_.components)
      by_node_[c.node][c.device];
    for (const auto &c : app_.connections)
      for (const auto *end : {&c.uses_end, &c.provides_end})
        if (*end && (*end)->device)
          by_node_[node_of_device(*(*end)->device)][*(*end)->device] = true;
  }

  void write_clusters() {
    std::size_t node_index = 0;
    for (const auto &[node, devices] : by_node_) {
      out_ += fmt::format("  subgraph cluster_n{} {{\n    label={};\n    style=rounded;\n",
                          node_index++, dot_string(node.empty() ? "(no node)" : node));
      for (const auto &[device, is_end] : devices)
        write_device(device, is_end);
      out_ += "  }\n";
    }
  }

  void write_device(const std::string &device, bool is_end) {
    const std::size_t index = device_ids_.size();
    device_ids_[device] = fmt::format("d{}", index);
    out_ += fmt::format("    subgraph cluster_d{} {{\n      label={};\n      style=dashed;\n",
                        index, dot_string(device));
    if (is_end)
      out_ += fmt::format("      d{} [label={}, shape=box3d];\n", index, dot_string(device));
    for (std::size_t i = 0; i < app_.components.size(); ++i)
      if (app_.components[i].device == device)
        write_component(app_.components[i], i);
    out_ += "    }\n";
  }

  void write_component(const app_ops::ComponentView &c, std::size_t index) {
    std::vector<std::string> lines{c.id, std::string(protocol::enum_name(c.state))};
    if (c.assembly_controller)
      lines.emplace_back("assembly controller");
    out_ += fmt::format("      c{} [label={}, shape=box, style=\"rounded,filled\", "
                        "fillcolor={}];\n",
                        index, dot_lines(lines), component_colour(c.state));
  }

  std::optional<std::string> component_id(const std::string &id) const {
    for (std::size_t i = 0; i < app_.components.size(); ++i)
      if (app_.components[i].id == id)
        return fmt::format("c{}", i);
    return std::nullopt;
  }

  // The event channel's node, written when first met.
  std::string channel_id(const std::string &name) {
    if (auto it = channel_ids_.find(name); it != channel_ids_.end())
      return it->second;
    const std::string id = fmt::format("ch{}", channel_ids_.size());
    channel_ids_[name] = id;
    out_ += fmt::format("  {} [label={}, shape=hexagon, style=filled, fillcolor=lightblue];\n", id,
                        dot_lines({name, "event channel"}));
    return id;
  }

  // A node of the graph for an owner that is not of this application (a reply from another
  // version of the domain): its name as given.
  std::string other_id(const std::string &name) {
    const std::string id = fmt::format("o{}", other_count_++);
    out_ += fmt::format("  {} [label={}, shape=plaintext];\n", id, dot_string(name));
    return id;
  }

  // The graph's node for one end of `c`: a component, a device, or the channel.
  std::string end_id(const app_ops::SadConnectionView &c, const std::optional<PortEnd> &end,
                     const std::string &name) {
    if (!end)
      return channel_id(c.channel.value_or(c.topic));
    if (end->device)
      return device_ids_.at(*end->device);
    if (auto id = component_id(end->component.value_or("")))
      return *id;
    return other_id(name);
  }

  void write_connection(const app_ops::SadConnectionView &c) {
    const std::string from = end_id(c, c.uses_end, c.uses);
    const std::string to = end_id(c, c.provides_end, c.provides);
    const EdgeLook look = look_of(c.state);
    std::vector<std::string> lines{fmt::format("{} ({})", c.id, look.word)};
    const std::string uses_port = c.uses_end ? c.uses_end->port : "";
    const std::string provides_port = c.provides_end ? c.provides_end->port : "";
    if (c.topic.empty())
      lines.push_back(fmt::format("{} calls its interface", uses_port));
    else
      lines.push_back(fmt::format("{} -> {}", uses_port.empty() ? "channel" : uses_port,
                                  provides_port.empty() ? "channel" : provides_port));
    if (auto qos = qos_text(c.qos); !qos.empty())
      lines.push_back(qos);
    if (c.filter)
      lines.push_back("filter " + *c.filter);
    out_ += fmt::format("  {} -> {} [label={}, color={}, fontcolor={}, style={}];\n", from, to,
                        dot_lines(lines), look.colour, look.colour, look.style);
  }

  void write_external_port(const app_ops::ExternalPortView &p, std::size_t index) {
    const auto component = component_id(p.component);
    if (!component)
      return;
    const bool uses = p.kind == "uses";
    out_ += fmt::format("  x{} [label={}, shape=cds, style=filled, fillcolor=white];\n", index,
                        dot_lines({p.name, fmt::format("external {} port", p.kind)}));
    const std::string port = dot_string(p.port);
    if (uses)
      out_ += fmt::format("  {} -> x{} [label={}, style=dotted];\n", *component, index, port);
    else
      out_ += fmt::format("  x{} -> {} [label={}, style=dotted];\n", index, *component, port);
  }

  const app_ops::ApplicationView &app_;
  // node -> device -> whether a connection reaches the device's own port
  std::map<std::string, std::map<std::string, bool>> by_node_;
  std::map<std::string, std::string> device_ids_;
  std::map<std::string, std::string> channel_ids_;
  std::size_t other_count_ = 0;
  std::string out_;
};

} // namespace

std::string dot_string(std::string_view text) {
  std::string out = "\"";
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_length(text, i);
    if (n > 1)
      out.append(text.substr(i, n));
    else if (n == 1)
      append_ascii(out, text[i]);
    else
      out += '?';
    i += n == 0 ? 1 : n;
  }
  return out + '"';
}

std::string application_dot(const app_ops::ApplicationView &app) {
  return Graph(app).write();
}

} // namespace rsca::cli
