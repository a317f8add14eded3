// The CLI's property syntax (profile/property_arguments.hpp) read into each PRF form and bound.
#include "profile/property_arguments.hpp"
#include "profile/property_binding.hpp"
#include "profile/property_json.hpp"

#include <catch2/catch.hpp>

namespace {

using rsca::profile::PropertyDefinition;

// `text` for `definition`, bound, as JSON; or the error text.
std::string argument_as_json(const PropertyDefinition &definition, const std::string &text) {
  auto ref = rsca::profile::ref_from_argument(definition, text);
  if (!ref)
    return "error: " + ref.error();
  auto bound = rsca::profile::bind_property(definition, *ref);
  if (!bound)
    return "error: " + bound.error().to_string();
  return rsca::profile::to_json(*bound).dump();
}

rsca::profile::SimpleProperty argument_simple(const std::string &id, rsca::profile::SimpleType t) {
  rsca::profile::SimpleProperty p;
  p.id = id;
  p.type.type = t;
  return p;
}

// gains: sequence of double; limit: {name string, steps sequence of long}; limits: a sequence
// of limit.
struct ArgumentDefinitions {
  PropertyDefinition gains, limit, limits;
  ArgumentDefinitions() {
    using rsca::profile::SimpleType;
    rsca::profile::SimpleSequenceProperty seq;
    seq.id = "gains";
    seq.type.type = SimpleType::Double;
    gains = seq;
    rsca::profile::StructProperty s;
    s.id = "limit";
    s.members.emplace_back(argument_simple("name", SimpleType::String));
    rsca::profile::SimpleSequenceProperty steps;
    steps.id = "steps";
    steps.type.type = SimpleType::Long;
    s.members.emplace_back(steps);
    limit = s;
    rsca::profile::StructSequenceProperty ss;
    ss.id = "limits";
    ss.element = s;
    limits = ss;
  }
};

} // namespace

TEST_CASE("the CLI's property syntax: sequences, structs and struct sequences, quoted items",
          "[profile][property_arguments]") {
  const ArgumentDefinitions d;
  CHECK(argument_as_json(d.gains, "[1, 2.5,3]") == "[1.0,2.5,3.0]");
  CHECK(argument_as_json(d.gains, "1,2") == "[1.0,2.0]");
  CHECK(argument_as_json(d.gains, "[]") == "[]");
  CHECK(argument_as_json(d.limit, "{name=\"a, {b}\",steps=[1,2]}") ==
        R"({"name":"a, {b}","steps":[1,2]})");
  CHECK(argument_as_json(d.limits, "[{name=x,steps=[]},{name=y,steps=[3]}]") ==
        R"([{"name":"x","steps":[]},{"name":"y","steps":[3]}])");
}

TEST_CASE("the CLI's property syntax refuses malformed text, naming the property",
          "[profile][property_arguments]") {
  const ArgumentDefinitions d;
  CHECK_THAT(argument_as_json(d.gains, "[1,2"), Catch::Contains("\"gains\": an unclosed bracket"));
  CHECK_THAT(argument_as_json(d.gains, "[1,{2}]"), Catch::Contains("is not one value"));
  CHECK_THAT(argument_as_json(d.limit, "name=x"),
             Catch::Contains("\"limit\": \"name=x\" is not a struct"));
  CHECK_THAT(argument_as_json(d.limit, "{name}"), Catch::Contains("is not member=value"));
  CHECK_THAT(argument_as_json(d.limit, "{nome=x}"), Catch::Contains("no member \"nome\""));
  CHECK_THAT(argument_as_json(d.limits, "{name=x}"),
             Catch::Contains("is not a sequence of structs"));
  CHECK_THAT(argument_as_json(d.gains, "[1,\"x]"), Catch::Contains("an unterminated quote"));
}
