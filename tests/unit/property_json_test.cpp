// Property values as JSON: the encoding of docs/architecture.md, and the checks a configure makes.
#include "profile/property_json.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <complex>
#include <string>

#include "profile/profile_loader.hpp"

using namespace rsca::profile;
using Json = nlohmann::json;

namespace {

SimpleProperty simple(std::string id, SimpleType type, bool complex = false) {
  SimpleProperty p;
  p.id = std::move(id);
  p.type = TypeSpec{type, complex};
  return p;
}

SimpleSequenceProperty sequence(std::string id, SimpleType type) {
  SimpleSequenceProperty p;
  p.id = std::move(id);
  p.type = TypeSpec{type, false};
  return p;
}

StructProperty stream_struct() {
  StructProperty s;
  s.id = "stream";
  s.members.emplace_back(simple("stream_id", SimpleType::String));
  auto rate = simple("sample_rate", SimpleType::Double);
  rate.range = ValueRange{Scalar(0.0), Scalar(1e6)};
  s.members.emplace_back(rate);
  s.members.emplace_back(sequence("taps", SimpleType::Float));
  return s;
}

PropertyValue value_of(const PropertyDefinition &definition, const Json &json) {
  INFO("JSON " << json.dump());
  auto value = from_json(definition, json);
  if (!value)
    FAIL("unexpected error: " << value.error());
  return *value;
}

std::string error_of(const PropertyDefinition &definition, const Json &json) {
  INFO("JSON " << json.dump());
  auto value = from_json(definition, json);
  REQUIRE_FALSE(value.has_value());
  return value.error();
}

template <typename T>
T scalar_of(const PropertyDefinition &definition, const Json &json) {
  const auto value = value_of(definition, json);
  REQUIRE(std::holds_alternative<Scalar>(value));
  REQUIRE(std::holds_alternative<T>(std::get<Scalar>(value)));
  return std::get<T>(std::get<Scalar>(value));
}

// from_json then to_json gives the JSON back.
void round_trips(const PropertyDefinition &definition, const Json &json) {
  INFO("JSON " << json.dump());
  CHECK(to_json(value_of(definition, json)) == json);
}

} // namespace

TEST_CASE("scalars encode as JSON numbers, booleans and strings", "[property_json]") {
  CHECK(to_json(Scalar(true)) == Json(true));
  CHECK(to_json(Scalar('x')) == Json("x"));
  CHECK(to_json(Scalar(std::uint8_t{200})) == Json(200));
  CHECK(to_json(Scalar(std::int16_t{-5})) == Json(-5));
  CHECK(to_json(Scalar(std::uint64_t{18446744073709551615ULL})) == Json(18446744073709551615ULL));
  CHECK(to_json(Scalar(2.5)) == Json(2.5));
  CHECK(to_json(Scalar(0.1F)) == Json(0.1)); // the float's shortest text, not 0.10000000149...
  CHECK(to_json(Scalar(std::string("hello"))) == Json("hello"));
}

TEST_CASE("complex, utctime and non-finite values encode as their profile text",
          "[property_json]") {
  CHECK(to_json(Scalar(std::complex<double>(1.5, 2))) == Json("1.5+j2"));
  CHECK(to_json(Scalar(std::complex<double>(0, -1))) == Json("0-j1"));
  const auto time = parse_scalar(TypeSpec{SimpleType::UtcTime, false}, "2024:01:31::12:00:00.5");
  REQUIRE(time.has_value());
  CHECK(to_json(*time) == Json("2024:01:31::12:00:00.500000"));
  CHECK(to_json(Scalar(std::nan(""))) == Json("nan"));
  CHECK(to_json(Scalar(-HUGE_VAL)) == Json("-inf"));
}

TEST_CASE("sequences, structs and struct sequences encode as arrays and objects",
          "[property_json]") {
  CHECK(to_json(PropertyValue(std::vector<Scalar>{Scalar(1), Scalar(2)})) == Json::array({1, 2}));
  StructValue s;
  s.members.emplace_back("stream_id", Scalar(std::string("a")));
  s.members.emplace_back("taps", std::vector<Scalar>{Scalar(1.0F)});
  const Json object = {{"stream_id", "a"}, {"taps", {1.0}}};
  CHECK(to_json(PropertyValue(s)) == object);
  CHECK(to_json(PropertyValue(std::vector<StructValue>{s, s})) == Json::array({object, object}));
}

TEST_CASE("values of every simple type are read in their declared type", "[property_json]") {
  CHECK(scalar_of<bool>(simple("b", SimpleType::Boolean), true));
  CHECK(scalar_of<char>(simple("c", SimpleType::Char), "z") == 'z');
  CHECK(scalar_of<std::uint8_t>(simple("o", SimpleType::Octet), 255) == 255);
  CHECK(scalar_of<std::int16_t>(simple("s", SimpleType::Short), -32768) == -32768);
  CHECK(scalar_of<std::uint16_t>(simple("us", SimpleType::UShort), 65535) == 65535);
  CHECK(scalar_of<std::int32_t>(simple("l", SimpleType::Long), 5.0) == 5); // an integral number
  CHECK(scalar_of<std::uint32_t>(simple("ul", SimpleType::ULong), 4000000000U) == 4000000000U);
  CHECK(scalar_of<std::int64_t>(simple("ll", SimpleType::LongLong), -9000000000LL) ==
        -9000000000LL);
  CHECK(scalar_of<std::uint64_t>(simple("ull", SimpleType::ULongLong), 18446744073709551615ULL) ==
        18446744073709551615ULL);
  CHECK(scalar_of<float>(simple("f", SimpleType::Float), 0.25) == 0.25F);
  CHECK(scalar_of<double>(simple("d", SimpleType::Double), 3) == 3.0); // an integer is a double
  CHECK(std::isinf(scalar_of<double>(simple("d", SimpleType::Double), "inf")));
  CHECK(scalar_of<std::string>(simple("str", SimpleType::String), "text") == "text");
  CHECK(scalar_of<std::complex<double>>(simple("cx", SimpleType::Float, true), "1.5+j2") ==
        std::complex<double>(1.5, 2));
  CHECK(scalar_of<UtcTime>(simple("t", SimpleType::UtcTime), "1970:01:01::00:00:01").seconds == 1);
}

TEST_CASE("a value of the wrong JSON type is refused, naming the property", "[property_json]") {
  CHECK(error_of(simple("rate_hz", SimpleType::Double), "fast") ==
        "property \"rate_hz\": \"fast\" is not a double");
  CHECK(error_of(simple("on", SimpleType::Boolean), 1) == "property \"on\": 1 is not a boolean");
  CHECK(error_of(simple("n", SimpleType::Long), 2.5) == "property \"n\": 2.5 is not a long");
  CHECK(error_of(simple("n", SimpleType::Long), "5") == "property \"n\": \"5\" is not a long");
  CHECK(error_of(simple("c", SimpleType::Char), "ab") == "property \"c\": \"ab\" is not a char");
  CHECK(error_of(simple("s", SimpleType::String), 5) == "property \"s\": 5 is not a string");
  CHECK(error_of(simple("cx", SimpleType::Double, true), 1.5) ==
        "property \"cx\": 1.5 is not a complex double");
  CHECK(error_of(sequence("seq", SimpleType::Long), 1) ==
        "property \"seq\": 1 is not an array of long");
  CHECK_THAT(error_of(simple("t", SimpleType::UtcTime), "yesterday"),
             Catch::StartsWith("property \"t\": \"yesterday\" is not a valid utctime"));
}

TEST_CASE("numbers outside their type or the PRF range are refused", "[property_json]") {
  CHECK(error_of(simple("s", SimpleType::Short), 70000) ==
        "property \"s\": 70000 is out of range for short (-32768..32767)");
  CHECK(error_of(simple("u", SimpleType::ULong), -1) ==
        "property \"u\": -1 is out of range for ulong (0..4294967295)");
  CHECK(error_of(simple("o", SimpleType::Octet), 256.0) ==
        "property \"o\": 256.0 is out of range for octet (0..255)");
  CHECK(error_of(simple("f", SimpleType::Float), 1e39) ==
        "property \"f\": 1e+39 is out of range for float");
  auto rate = simple("rate_hz", SimpleType::Double);
  rate.range = ValueRange{Scalar(0.1), Scalar(10000.0)};
  CHECK(scalar_of<double>(rate, 10000) == 10000.0);
  CHECK(error_of(rate, 1e9) ==
        "property \"rate_hz\": 1000000000.0 is outside its range 0.1..10000");
  auto seq = sequence("gains", SimpleType::Long);
  seq.range = ValueRange{Scalar(std::int32_t{0}), Scalar(std::int32_t{10})};
  CHECK(error_of(seq, Json::array({1, 11})) ==
        "property \"gains\": element 1: 11 is outside its range 0..10");
}

TEST_CASE("a simple with enumerations takes their values or labels only", "[property_json]") {
  auto mode = simple("mode", SimpleType::Short);
  mode.enumerations = {{"off", Scalar(std::int16_t{0})}, {"on", Scalar(std::int16_t{1})}};
  CHECK(scalar_of<std::int16_t>(mode, "on") == 1);
  CHECK(scalar_of<std::int16_t>(mode, 0) == 0);
  CHECK(error_of(mode, 2) == "property \"mode\": 2 is none of its enumerations: off (0), on (1)");
  CHECK(error_of(mode, "auto") == "property \"mode\": \"auto\" is not a short");
}

TEST_CASE("structs are objects of their members, unknown members are refused", "[property_json]") {
  const PropertyDefinition stream = stream_struct();
  round_trips(stream, {{"stream_id", "s1"}, {"sample_rate", 48000.0}, {"taps", {0.5, 0.25}}});
  // A configure may name some members only.
  const auto partial = std::get<StructValue>(value_of(stream, {{"sample_rate", 8000}}));
  REQUIRE(partial.members.size() == 1);
  CHECK(partial.members[0].first == "sample_rate");
  CHECK(error_of(stream, {{"rate", 1.0}}) ==
        "property \"stream\": struct \"stream\" has no member \"rate\"");
  CHECK(error_of(stream, {{"sample_rate", -1.0}}) ==
        "property \"stream\": member \"sample_rate\": -1.0 is outside its range 0..1e+06");
  CHECK(error_of(stream, Json::array()) ==
        "property \"stream\": [] is not an object of struct members");
}

TEST_CASE("struct sequences are arrays of objects", "[property_json]") {
  StructSequenceProperty streams;
  streams.id = "streams";
  streams.element = stream_struct();
  const PropertyDefinition definition = streams;
  round_trips(definition,
              Json::array({{{"stream_id", "a"}}, {{"stream_id", "b"}, {"taps", {1.0}}}}));
  CHECK(error_of(definition, Json::array({{{"stream_id", "a"}}, {{"stream_id", 3}}})) ==
        "property \"streams\": element 1: member \"stream_id\": 3 is not a string");
}

TEST_CASE("the Producer's PRF properties read from JSON", "[property_json]") {
  ProfileLoader loader;
  auto softpkg =
      loader.load_softpkg(RSCA_SOURCE_DIR "/profiles/dom/components/Producer/Producer.spd.xml");
  REQUIRE(softpkg.has_value());
  const auto *rate = (*softpkg)->find_property("rate_hz");
  const auto *stream = (*softpkg)->find_property("stream");
  REQUIRE(rate != nullptr);
  REQUIRE(stream != nullptr);
  CHECK(scalar_of<double>(*rate, 250.5) == 250.5);
  CHECK_THAT(error_of(*rate, 0.01), Catch::Contains("outside its range 0.1..10000"));
  round_trips(*stream, {{"stream_id", "imu"}, {"sample_rate", 200.0}});
  // The PRF defaults encode as configure would take them.
  const auto defaults = default_value(*stream);
  REQUIRE(defaults.has_value());
  CHECK(to_json(*defaults) == Json{{"stream_id", "producer"}, {"sample_rate", 1000.0}});
}
