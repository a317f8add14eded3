// The picture of a running application (`rsca show APP --graph dot|svg`): app.show's reply as
// Graphviz DOT text. A cluster per node and, within it, one per device, holding the components
// that device runs (and the device itself when a connection reaches its port); an edge per
// connection, labelled with its ports and QoS and drawn by its live state; an event channel as a
// node of its own, its publishers' edges into it and its subscribers' out of it; the SAD's
// external ports. A pure function of the reply, so that it is tested without a domain; every
// name in it comes from profiles or from the network, and is escaped as such.
#pragma once

#include <string>
#include <string_view>

#include "protocol/application_ops.hpp"

namespace rsca::cli {

// `text` as a DOT string with its quotes: a quote or a backslash escaped, a line break as DOT's
// \n, any other control character and any byte that is not UTF-8 as '?', so that nothing in it
// ends the string or reads as a Graphviz escape.
std::string dot_string(std::string_view text);

// The application as a DOT digraph.
std::string application_dot(const protocol::application::ApplicationView &app);

} // namespace rsca::cli
