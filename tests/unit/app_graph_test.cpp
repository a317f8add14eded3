// The picture of a running application (tools/rsca/app_graph.hpp): app.show's reply as DOT, its
// clusters, nodes and edges read back from the text, and names from the network that stay one
// escaped DOT string whatever they hold.
#include <catch2/catch.hpp>

#include <algorithm>
#include <string>
#include <vector>

#include "app_graph.hpp"

namespace {

namespace app_ops = rsca::protocol::application;
using rsca::cli::application_dot;
using rsca::cli::dot_string;
using rsca::protocol::Json;
using rsca::protocol::connection::ConnectionState;
using rsca::protocol::connection::PortEnd;

app_ops::ComponentView running_component(const std::string &id, const std::string &node,
                                         const std::string &device) {
  app_ops::ComponentView c;
  c.id = id;
  c.usage_name = id;
  c.node = node;
  c.device = device;
  c.state = app_ops::ComponentState::Running;
  return c;
}

PortEnd app_port(const std::string &component, const std::string &port) {
  return PortEnd{"PC", component, std::nullopt, port};
}

app_ops::SadConnectionView sad_connection(const std::string &id, std::optional<PortEnd> uses,
                                          std::optional<PortEnd> provides) {
  app_ops::SadConnectionView c;
  c.id = id;
  c.topic = "rsca_topic_" + id;
  c.qos = Json{{"reliability", "reliable"},
               {"history", "keeplast"},
               {"depth", 16},
               {"deadline_ns", 100'000'000}};
  c.uses_end = std::move(uses);
  c.provides_end = std::move(provides);
  return c;
}

// Producer_1 and Relay_1 on node1's GPP, Consumer_1 on node2's; Producer_1 -> Consumer_1.
app_ops::ApplicationView producer_consumer() {
  app_ops::ApplicationView app;
  app.name = "PC";
  app.installed = "ProducerConsumer";
  app.state = "running";
  app.components = {running_component("Producer_1", "node1", "node1:GPP_1"),
                    running_component("Relay_1", "node1", "node1:GPP_1"),
                    running_component("Consumer_1", "node2", "node2:GPP_1")};
  auto samples = sad_connection("samples", app_port("Producer_1", "samples_out"),
                                app_port("Consumer_1", "samples_in"));
  samples.state = ConnectionState::Connected;
  app.connections = {samples};
  return app;
}

// The text of the block that opens on the first line holding `opening` (up to its closing
// brace); empty when there is none.
std::string dot_block(const std::string &dot, const std::string &opening) {
  const auto start = dot.find(opening);
  if (start == std::string::npos)
    return {};
  int depth = 0;
  bool quoted = false;
  for (std::size_t i = dot.find('{', start); i < dot.size(); ++i) {
    if (quoted && dot[i] == '\\')
      ++i;
    else if (dot[i] == '"')
      quoted = !quoted;
    else if (!quoted && dot[i] == '{')
      ++depth;
    else if (!quoted && dot[i] == '}' && --depth == 0)
      return dot.substr(start, i + 1 - start);
  }
  return {};
}

// The cluster labelled `label`: its subgraph line and its contents.
std::string dot_cluster(const std::string &dot, const std::string &label) {
  const auto at = dot.find("label=" + dot_string(label) + ";");
  if (at == std::string::npos)
    return {};
  const auto line = dot.rfind("subgraph cluster_", at);
  return line == std::string::npos ? std::string() : dot_block(dot, dot.substr(line, at - line));
}

// The id of the graph's node whose attributes begin with `attributes`.
std::string node_with(const std::string &dot, const std::string &attributes) {
  const auto at = dot.find(" [" + attributes);
  if (at == std::string::npos)
    return {};
  const auto line = dot.rfind('\n', at) + 1;
  const std::string id = dot.substr(line, at - line);
  return id.substr(id.find_first_not_of(' '));
}

// The id of the graph's node whose label's first line is `first_line`.
std::string node_id(const std::string &dot, const std::string &first_line) {
  return node_with(dot, "label=\"" + first_line + "\\n");
}

// The edge line from `from` to `to`; empty when there is none.
std::string dot_edge(const std::string &dot, const std::string &from, const std::string &to) {
  const auto at = dot.find("  " + from + " -> " + to + " [");
  if (at == std::string::npos)
    return {};
  return dot.substr(at, dot.find('\n', at) - at);
}

// Every quoted string of every line is closed on that line: no raw line break, stray quote or
// escaping backslash got into one.
bool strings_closed(const std::string &dot) {
  bool quoted = false;
  for (std::size_t i = 0; i < dot.size(); ++i) {
    if (dot[i] == '\n' && quoted)
      return false;
    if (quoted && dot[i] == '\\')
      ++i;
    else if (dot[i] == '"')
      quoted = !quoted;
  }
  return !quoted;
}

} // namespace

TEST_CASE("app graph: a cluster per node, in it a cluster per device, a graph node per component",
          "[app_graph]") {
  const std::string dot = application_dot(producer_consumer());
  INFO(dot);
  CHECK(dot.rfind("digraph \"PC\" {", 0) == 0);
  const std::string node1 = dot_cluster(dot, "node1");
  const std::string node2 = dot_cluster(dot, "node2");
  const std::string gpp1 = dot_cluster(dot, "node1:GPP_1");
  REQUIRE_FALSE(node1.empty());
  REQUIRE_FALSE(node2.empty());
  REQUIRE_FALSE(gpp1.empty());
  CHECK(node1.find(gpp1) != std::string::npos); // the device's cluster within its node's
  CHECK(node1.find("node2:GPP_1") == std::string::npos);
  CHECK(node2.find(dot_string("node2:GPP_1")) != std::string::npos);
  for (const char *id : {"Producer_1", "Relay_1"}) {
    INFO(id);
    const std::string graph_node = node_id(dot, id);
    REQUIRE_FALSE(graph_node.empty());
    CHECK(gpp1.find("      " + graph_node + " [label=") != std::string::npos);
  }
  const std::string consumer = node_id(dot, "Consumer_1");
  REQUIRE_FALSE(consumer.empty());
  CHECK(node2.find(consumer + " [label=") != std::string::npos);
  CHECK(node1.find(consumer + " [label=") == std::string::npos);
  // One graph node per component: each label once.
  for (const char *id : {"Producer_1", "Relay_1", "Consumer_1"}) {
    const std::string label = std::string("[label=\"") + id + "\\n";
    CHECK(dot.find(label) != std::string::npos);
    CHECK(dot.find(label, dot.find(label) + 1) == std::string::npos);
  }
  CHECK(strings_closed(dot));
}

TEST_CASE("app graph: an edge per connection with its ports and QoS, drawn by its live state",
          "[app_graph]") {
  auto app = producer_consumer();
  auto relayed = sad_connection("relayed", app_port("Producer_1", "samples_out"),
                                app_port("Relay_1", "samples_in"));
  relayed.state = ConnectionState::Failed;
  relayed.qos = Json{{"reliability", "besteffort"}, {"history", "keepall"}};
  auto unknown = sad_connection("unknown", app_port("Relay_1", "samples_out"),
                                app_port("Consumer_1", "samples_in"));
  app.connections.push_back(relayed);
  app.connections.push_back(unknown);
  const std::string dot = application_dot(app);
  INFO(dot);
  const std::string producer = node_id(dot, "Producer_1");
  const std::string relay = node_id(dot, "Relay_1");
  const std::string consumer = node_id(dot, "Consumer_1");

  const std::string samples = dot_edge(dot, producer, consumer);
  REQUIRE_FALSE(samples.empty());
  CHECK(samples.find("samples (connected)") != std::string::npos);
  CHECK(samples.find("samples_out -> samples_in") != std::string::npos);
  CHECK(samples.find("reliable, keeplast(16), deadline 100ms") != std::string::npos);
  CHECK(samples.find("style=solid") != std::string::npos);

  const std::string failed = dot_edge(dot, producer, relay);
  REQUIRE_FALSE(failed.empty());
  CHECK(failed.find("relayed (failed)") != std::string::npos);
  CHECK(failed.find("besteffort, keepall\"") != std::string::npos);
  CHECK(failed.find("color=red") != std::string::npos);

  const std::string not_told = dot_edge(dot, relay, consumer);
  REQUIRE_FALSE(not_told.empty());
  CHECK(not_told.find("unknown (unknown)") != std::string::npos);
  CHECK(not_told.find("style=dotted") != std::string::npos);
  CHECK(strings_closed(dot));
}

TEST_CASE("app graph: an event channel is a node of its own, publishers into it and subscribers "
          "out of it",
          "[app_graph]") {
  auto app = producer_consumer();
  auto publish = sad_connection("publish", app_port("Producer_1", "events_out"), std::nullopt);
  publish.channel = "Ticks";
  publish.state = ConnectionState::Pending;
  auto all = sad_connection("all", std::nullopt, app_port("Consumer_1", "events_in"));
  all.channel = "Ticks";
  all.filter = "sequence < 50";
  app.connections = {publish, all};
  const std::string dot = application_dot(app);
  INFO(dot);
  const std::string channel = node_id(dot, "Ticks");
  REQUIRE_FALSE(channel.empty());
  CHECK(dot.find(channel + " [label=\"Ticks\\nevent channel\", shape=hexagon") !=
        std::string::npos);
  CHECK(dot.find("[label=\"Ticks\\n", dot.find("[label=\"Ticks\\n") + 1) == std::string::npos);
  const std::string into = dot_edge(dot, node_id(dot, "Producer_1"), channel);
  REQUIRE_FALSE(into.empty());
  CHECK(into.find("publish (pending)") != std::string::npos);
  CHECK(into.find("events_out -> channel") != std::string::npos);
  CHECK(into.find("style=dashed") != std::string::npos);
  const std::string out_of = dot_edge(dot, channel, node_id(dot, "Consumer_1"));
  REQUIRE_FALSE(out_of.empty());
  CHECK(out_of.find("channel -> events_in") != std::string::npos);
  CHECK(out_of.find("filter sequence < 50") != std::string::npos);
  CHECK(strings_closed(dot));
}

TEST_CASE("app graph: a device's port is drawn in its node's cluster, and external ports beside "
          "their component",
          "[app_graph]") {
  auto app = producer_consumer();
  auto ranges =
      sad_connection("ranges", PortEnd{std::nullopt, std::nullopt, "robot:IRSensor_1", "out"},
                     app_port("Consumer_1", "samples_in"));
  app.connections.push_back(ranges);
  app.external_ports = {{"samples_tap", "Producer_1", "samples_out", "uses"},
                        {"control", "Consumer_1", "control_in", "provides"}};
  const std::string dot = application_dot(app);
  INFO(dot);
  const std::string robot = dot_cluster(dot, "robot");
  REQUIRE_FALSE(robot.empty());
  const std::string sensor = node_with(dot, "label=\"robot:IRSensor_1\", shape=box3d]");
  REQUIRE_FALSE(sensor.empty());
  CHECK(robot.find(sensor + " [label=") != std::string::npos);
  CHECK_FALSE(dot_edge(dot, sensor, node_id(dot, "Consumer_1")).empty());
  const std::string tap = node_id(dot, "samples_tap");
  const std::string control = node_id(dot, "control");
  REQUIRE_FALSE(tap.empty());
  REQUIRE_FALSE(control.empty());
  CHECK_FALSE(dot_edge(dot, node_id(dot, "Producer_1"), tap).empty());
  CHECK_FALSE(dot_edge(dot, control, node_id(dot, "Consumer_1")).empty());
  CHECK(strings_closed(dot));
}

TEST_CASE("app graph: a hostile name (quote, backslash, line break) stays one escaped DOT string",
          "[app_graph]") {
  CHECK(dot_string("plain") == "\"plain\"");
  CHECK(dot_string("a\"b") == "\"a\\\"b\"");
  CHECK(dot_string("a\\") == "\"a\\\\\"");
  CHECK(dot_string("a\nb") == "\"a\\nb\"");
  CHECK(dot_string("\\N\\G") == "\"\\\\N\\\\G\""); // not Graphviz's node or graph name
  CHECK(dot_string(std::string("a\0\x1b\r", 4)) == "\"a???\"");
  CHECK(dot_string("caf\xc3\xa9") == "\"caf\xc3\xa9\""); // UTF-8 kept
  CHECK(dot_string("bad\xc3") == "\"bad?\"");            // a cut sequence is not

  // Every name the reply carries, from profiles or from the network, is `name`.
  const auto named = [](const std::string &name) {
    auto app = producer_consumer();
    app.name = name;
    app.components[0].id = name;
    app.components[0].node = name;
    app.components[0].device = name + ":GPP_1";
    app.connections[0].id = name;
    app.connections[0].uses_end = app_port(name, "out\\");
    app.external_ports = {{name, name, "p\"", "uses"}};
    return app;
  };
  const std::string hostile = "Evil\"];\nx -> y [label=\"\\";
  const std::string dot = application_dot(named(hostile));
  INFO(dot);
  CHECK(strings_closed(dot));
  CHECK(dot.find(hostile) == std::string::npos); // never raw
  const std::string escaped = "Evil\\\"];\\nx -> y [label=\\\"\\\\";
  CHECK(dot.find("digraph \"" + escaped + "\" {") == 0);
  CHECK(dot.find("label=\"" + escaped + "\";") != std::string::npos); // its node's cluster
  CHECK(dot.find("[label=\"" + escaped + "\\nrunning") != std::string::npos);
  CHECK(dot.find("\"" + escaped + " (connected)\\nout\\\\ -> samples_in") != std::string::npos);
  // The component's graph node is still the edge's tail: the edge found its end by id.
  const std::string tail = node_id(dot, escaped);
  REQUIRE_FALSE(tail.empty());
  CHECK_FALSE(dot_edge(dot, tail, node_id(dot, "Consumer_1")).empty());
  // No more lines than the same graph with a plain name: nothing in a name began a statement.
  const auto lines = [](const std::string &text) {
    return std::count(text.begin(), text.end(), '\n');
  };
  CHECK(lines(dot) == lines(application_dot(named("Plain"))));
}
