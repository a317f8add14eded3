#include "profile/property_value.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

using namespace rsca::profile;

namespace {

constexpr TypeSpec simple(SimpleType type) {
  return TypeSpec{type, false};
}
constexpr TypeSpec complex_of(SimpleType type) {
  return TypeSpec{type, true};
}

// The value parse_scalar gives, which must be of alternative T.
template <class T>
T parsed(TypeSpec spec, std::string_view text) {
  INFO("type " << to_string(spec.type) << (spec.complex ? " complex" : "") << ", text \"" << text
               << "\"");
  const auto result = parse_scalar(spec, text);
  if (!result)
    FAIL("unexpected error: " << result.error());
  REQUIRE(std::holds_alternative<T>(*result));
  return std::get<T>(*result);
}

// The error parse_scalar gives.
std::string error_of(TypeSpec spec, std::string_view text) {
  INFO("type " << to_string(spec.type) << (spec.complex ? " complex" : "") << ", text \"" << text
               << "\"");
  const auto result = parse_scalar(spec, text);
  if (result)
    FAIL("parsed, but should not have: " << format_scalar(*result));
  return result.error();
}

bool rejects(TypeSpec spec, std::string_view text) {
  return !parse_scalar(spec, text).has_value();
}

template <class T>
Scalar scalar(T value) {
  return Scalar{std::in_place_type<T>, value};
}

UtcTime utc(std::int64_t seconds, std::uint32_t micros = 0) {
  return UtcTime{false, seconds, micros};
}

} // namespace

TEST_CASE("simple type names map both ways", "[property_value]") {
  const std::vector<std::pair<std::string_view, SimpleType>> names{
      {"boolean", SimpleType::Boolean},     {"char", SimpleType::Char},
      {"octet", SimpleType::Octet},         {"short", SimpleType::Short},
      {"ushort", SimpleType::UShort},       {"long", SimpleType::Long},
      {"ulong", SimpleType::ULong},         {"longlong", SimpleType::LongLong},
      {"ulonglong", SimpleType::ULongLong}, {"float", SimpleType::Float},
      {"double", SimpleType::Double},       {"string", SimpleType::String},
      {"objref", SimpleType::ObjRef},       {"utctime", SimpleType::UtcTime},
  };
  for (const auto &[name, type] : names) {
    CAPTURE(name);
    CHECK(simple_type_from_name(name) == type);
    CHECK(to_string(type) == name);
  }
  CHECK_FALSE(simple_type_from_name("int").has_value());
  CHECK_FALSE(simple_type_from_name("Short").has_value());
  CHECK_FALSE(simple_type_from_name("").has_value());
  CHECK_FALSE(simple_type_from_name(" short").has_value());
}

TEST_CASE("action names map both ways", "[property_value]") {
  const std::vector<std::pair<std::string_view, Action>> names{
      {"eq", Action::Eq},
      {"ne", Action::Ne},
      {"gt", Action::Gt},
      {"lt", Action::Lt},
      {"ge", Action::Ge},
      {"le", Action::Le},
      {"external", Action::External},
  };
  for (const auto &[name, action] : names) {
    CAPTURE(name);
    CHECK(action_from_name(name) == action);
    CHECK(to_string(action) == name);
  }
  CHECK_FALSE(action_from_name("EQ").has_value());
  CHECK_FALSE(action_from_name("equal").has_value());
  CHECK_FALSE(action_from_name("").has_value());
}

TEST_CASE("type classification", "[property_value]") {
  CHECK(is_integer(SimpleType::Octet));
  CHECK(is_integer(SimpleType::ULongLong));
  CHECK_FALSE(is_integer(SimpleType::Char));
  CHECK_FALSE(is_integer(SimpleType::Boolean));
  CHECK_FALSE(is_integer(SimpleType::Float));
  CHECK(is_floating(SimpleType::Float));
  CHECK(is_floating(SimpleType::Double));
  CHECK_FALSE(is_floating(SimpleType::Long));
  CHECK(is_numeric(SimpleType::Short));
  CHECK(is_numeric(SimpleType::Double));
  CHECK_FALSE(is_numeric(SimpleType::String));
  CHECK_FALSE(is_numeric(SimpleType::UtcTime));
  CHECK_FALSE(is_numeric(SimpleType::Boolean));
}

TEST_CASE("integer boundaries", "[property_value]") {
  SECTION("octet") {
    CHECK(parsed<std::uint8_t>(simple(SimpleType::Octet), "0") == 0);
    CHECK(parsed<std::uint8_t>(simple(SimpleType::Octet), "255") == 255);
    CHECK(error_of(simple(SimpleType::Octet), "256") ==
          "\"256\" is out of range for octet (0..255)");
    CHECK(error_of(simple(SimpleType::Octet), "-1") == "\"-1\" is out of range for octet (0..255)");
    CHECK(error_of(simple(SimpleType::Octet), "a") == "\"a\" is not a valid octet");
  }
  SECTION("short") {
    CHECK(parsed<std::int16_t>(simple(SimpleType::Short), "-32768") == -32768);
    CHECK(parsed<std::int16_t>(simple(SimpleType::Short), "32767") == 32767);
    CHECK(error_of(simple(SimpleType::Short), "32768") ==
          "\"32768\" is out of range for short (-32768..32767)");
    CHECK(error_of(simple(SimpleType::Short), "-32769") ==
          "\"-32769\" is out of range for short (-32768..32767)");
    CHECK(error_of(simple(SimpleType::Short), "70000") ==
          "\"70000\" is out of range for short (-32768..32767)");
  }
  SECTION("ushort") {
    CHECK(parsed<std::uint16_t>(simple(SimpleType::UShort), "0") == 0);
    CHECK(parsed<std::uint16_t>(simple(SimpleType::UShort), "65535") == 65535);
    CHECK(error_of(simple(SimpleType::UShort), "65536") ==
          "\"65536\" is out of range for ushort (0..65535)");
    CHECK(error_of(simple(SimpleType::UShort), "-1") ==
          "\"-1\" is out of range for ushort (0..65535)");
  }
  SECTION("long") {
    CHECK(parsed<std::int32_t>(simple(SimpleType::Long), "-2147483648") == INT32_MIN);
    CHECK(parsed<std::int32_t>(simple(SimpleType::Long), "2147483647") == INT32_MAX);
    CHECK(error_of(simple(SimpleType::Long), "2147483648") ==
          "\"2147483648\" is out of range for long (-2147483648..2147483647)");
    CHECK(rejects(simple(SimpleType::Long), "-2147483649"));
  }
  SECTION("ulong") {
    CHECK(parsed<std::uint32_t>(simple(SimpleType::ULong), "0") == 0);
    CHECK(parsed<std::uint32_t>(simple(SimpleType::ULong), "4294967295") == UINT32_MAX);
    CHECK(error_of(simple(SimpleType::ULong), "4294967296") ==
          "\"4294967296\" is out of range for ulong (0..4294967295)");
    CHECK(rejects(simple(SimpleType::ULong), "-1"));
  }
  SECTION("longlong") {
    CHECK(parsed<std::int64_t>(simple(SimpleType::LongLong), "-9223372036854775808") == INT64_MIN);
    CHECK(parsed<std::int64_t>(simple(SimpleType::LongLong), "9223372036854775807") == INT64_MAX);
    CHECK(error_of(simple(SimpleType::LongLong), "9223372036854775808") ==
          "\"9223372036854775808\" is out of range for longlong "
          "(-9223372036854775808..9223372036854775807)");
    CHECK(rejects(simple(SimpleType::LongLong), "-9223372036854775809"));
    CHECK(rejects(simple(SimpleType::LongLong), "-99999999999999999999999"));
  }
  SECTION("ulonglong") {
    CHECK(parsed<std::uint64_t>(simple(SimpleType::ULongLong), "0") == 0);
    CHECK(parsed<std::uint64_t>(simple(SimpleType::ULongLong), "18446744073709551615") ==
          UINT64_MAX);
    CHECK(error_of(simple(SimpleType::ULongLong), "18446744073709551616") ==
          "\"18446744073709551616\" is out of range for ulonglong (0..18446744073709551615)");
    CHECK(rejects(simple(SimpleType::ULongLong), "-1"));
  }
}

TEST_CASE("integer syntax: signs, hex, whitespace", "[property_value]") {
  const auto lng = simple(SimpleType::Long);
  CHECK(parsed<std::int32_t>(lng, "+42") == 42);
  CHECK(parsed<std::int32_t>(lng, "-0") == 0);
  CHECK(parsed<std::int32_t>(lng, "007") == 7);
  CHECK(parsed<std::int32_t>(lng, "  42\t\n") == 42);
  CHECK(parsed<std::int32_t>(lng, "0x7fffffff") == INT32_MAX);
  CHECK(parsed<std::int32_t>(lng, "0X1F") == 31);
  CHECK(parsed<std::int32_t>(lng, "-0x80000000") == INT32_MIN);
  CHECK(parsed<std::int32_t>(lng, "+0x10") == 16);
  CHECK(error_of(lng, "0x80000000") ==
        "\"0x80000000\" is out of range for long (-2147483648..2147483647)");
  CHECK(parsed<std::int16_t>(simple(SimpleType::Short), "-0x8000") == -32768);
  CHECK(rejects(simple(SimpleType::Short), "0x8000"));
  CHECK(parsed<std::uint8_t>(simple(SimpleType::Octet), "0xff") == 255);
  CHECK(rejects(simple(SimpleType::Octet), "0x100"));
  CHECK(parsed<std::uint64_t>(simple(SimpleType::ULongLong), "0xFFFFFFFFFFFFFFFF") == UINT64_MAX);
  CHECK(rejects(simple(SimpleType::ULongLong), "0x10000000000000000"));

  CHECK(error_of(simple(SimpleType::UShort), "-0") ==
        "\"-0\" is not a valid ushort (unsigned types take no minus sign)");
  CHECK(error_of(lng, "abc") == "\"abc\" is not a valid long");
  CHECK(error_of(lng, "") == "\"\" is not a valid long");
  CHECK(error_of(lng, "  ") == "\"\" is not a valid long");
  for (const auto *bad : {"+", "-", "--5", "+-5", "-+5", "5-", "4 2", "1.0", "1e3", "0x", "0xg",
                          "0x-1", "x10", "12abc", "1_000", "0b101", "\xef\xbc\x91"}) {
    CAPTURE(bad);
    CHECK(rejects(lng, bad));
  }
}

TEST_CASE("float parsing and its range", "[property_value]") {
  const auto flt = simple(SimpleType::Float);
  constexpr float kMax = std::numeric_limits<float>::max();
  CHECK(parsed<float>(flt, "3.402823466e38") == kMax);
  CHECK(parsed<float>(flt, "-3.402823466e38") == -kMax);
  CHECK(parsed<float>(flt, "3.4028235e+38") == kMax);
  // Too large for a float: rounds to an infinity of the same sign, as strtof does.
  CHECK(parsed<float>(flt, "3.5e38") == std::numeric_limits<float>::infinity());
  CHECK(parsed<float>(flt, "1e99") == std::numeric_limits<float>::infinity());
  CHECK(parsed<float>(flt, "-1e39") == -std::numeric_limits<float>::infinity());
  CHECK(parsed<float>(flt, "1.5") == 1.5F);
  CHECK(parsed<float>(flt, "+1.5") == 1.5F);
  CHECK(parsed<float>(flt, "-2.5e-3") == -2.5e-3F);
  CHECK(parsed<float>(flt, " 0.1 ") == 0.1F);
  CHECK(parsed<float>(flt, ".5") == 0.5F);
  CHECK(parsed<float>(flt, "7") == 7.0F);
  CHECK(std::isinf(parsed<float>(flt, "inf")));
  CHECK(parsed<float>(flt, "-inf") < 0);
  CHECK(std::isnan(parsed<float>(flt, "nan")));
  // Too small for a float: rounds to a zero of the same sign.
  CHECK(parsed<float>(flt, "1e-50") == 0.0F);
  CHECK(std::signbit(parsed<float>(flt, "-1e-50")));
  CHECK(parsed<float>(flt, "1e-40") > 0.0F);
  for (const auto *bad : {"", "abc", "1.5f", "1,5", "0x1p3", "++1", "+-1", "1e", "1.2.3", "e5",
                          "1 5", "- 1", "true"}) {
    CAPTURE(bad);
    CHECK(rejects(flt, bad));
  }
}

TEST_CASE("double parsing and its range", "[property_value]") {
  const auto dbl = simple(SimpleType::Double);
  CHECK(parsed<double>(dbl, "1.7976931348623157e308") == std::numeric_limits<double>::max());
  CHECK(parsed<double>(dbl, "3.5e38") == 3.5e38);
  CHECK(parsed<double>(dbl, "0.1") == 0.1);
  CHECK(parsed<double>(dbl, "-1E-3") == -1e-3);
  CHECK(parsed<double>(dbl, "4.9e-324") > 0.0);
  CHECK(parsed<double>(dbl, "1e-400") == 0.0);
  CHECK(std::signbit(parsed<double>(dbl, "-1e-99999999999999999999")));
  CHECK(parsed<double>(dbl, "1.8e308") == std::numeric_limits<double>::infinity());
  CHECK(parsed<double>(dbl, "-1e99999999999999999999") == -std::numeric_limits<double>::infinity());
  CHECK(parsed<double>(dbl, "123456789e301") == std::numeric_limits<double>::infinity());
  CHECK(parsed<double>(dbl, "0.000001e-320") == 0.0);
  CHECK(error_of(dbl, "abc") == "\"abc\" is not a valid double");
  CHECK(std::isinf(parsed<double>(dbl, "-inf")));
  CHECK(std::isnan(parsed<double>(dbl, "nan")));
}

TEST_CASE("boolean parsing", "[property_value]") {
  const auto b = simple(SimpleType::Boolean);
  CHECK(parsed<bool>(b, "true") == true);
  CHECK(parsed<bool>(b, "TRUE") == true);
  CHECK(parsed<bool>(b, "False") == false);
  CHECK(parsed<bool>(b, "1") == true);
  CHECK(parsed<bool>(b, "0") == false);
  CHECK(parsed<bool>(b, " true\n") == true);
  CHECK(error_of(b, "maybe") == "\"maybe\" is not a boolean (true or false)");
  for (const auto *bad : {"", "yes", "no", "2", "t", "truee", "01", "on"}) {
    CAPTURE(bad);
    CHECK(rejects(b, bad));
  }
}

TEST_CASE("char parsing", "[property_value]") {
  const auto c = simple(SimpleType::Char);
  CHECK(parsed<char>(c, "a") == 'a');
  CHECK(parsed<char>(c, " ") == ' ');
  CHECK(parsed<char>(c, " z ") == 'z');
  CHECK(parsed<char>(c, "7") == '7');
  CHECK(error_of(c, "ab") == "\"ab\" is not a single character");
  CHECK(rejects(c, ""));
  CHECK(rejects(c, "  "));
}

TEST_CASE("string and objref keep their text exactly", "[property_value]") {
  CHECK(parsed<std::string>(simple(SimpleType::String), "  two  words \n") == "  two  words \n");
  CHECK(parsed<std::string>(simple(SimpleType::String), "").empty());
  CHECK(parsed<std::string>(simple(SimpleType::ObjRef), "IOR:0001") == "IOR:0001");
}

TEST_CASE("utctime parsing", "[property_value]") {
  const auto t = simple(SimpleType::UtcTime);
  CHECK(parsed<UtcTime>(t, "1970:01:01::00:00:00") == utc(0));
  CHECK(parsed<UtcTime>(t, "2000:01:01::00:00:00") == utc(946684800));
  // 2000-01-01 is day 10957; +31 (January) +28 = day 11016; 12:34:56 is 45296 s.
  CHECK(parsed<UtcTime>(t, "2000:02:29::12:34:56.5") == utc(11016LL * 86400 + 45296, 500000));
  CHECK(parsed<UtcTime>(t, "2038:01:19::03:14:07") == utc(2147483647));
  CHECK(parsed<UtcTime>(t, "1969:12:31::23:59:59.999999") == utc(-1, 999999));
  CHECK(parsed<UtcTime>(t, "9999:12:31::23:59:59") == utc(253402300799));
  CHECK(parsed<UtcTime>(t, "0000:01:01::00:00:00") == utc(-62167219200));
  CHECK(parsed<UtcTime>(t, "2024:12:31::23:59:59.000001") == utc(1735689599, 1));
  CHECK(parsed<UtcTime>(t, "2001:03:01::00:00:00.123") == utc(983404800, 123000));
  CHECK(parsed<UtcTime>(t, " 2000:01:01::00:00:00 ") == utc(946684800));
  CHECK(parsed<UtcTime>(t, "now") == UtcTime{true, 0, 0});
  // REDHAWK writes the fields after the year with one digit too.
  CHECK(parsed<UtcTime>(t, "2017:2:1::12:01:00.123") ==
        parsed<UtcTime>(t, "2017:02:01::12:01:00.123"));
  CHECK(parsed<UtcTime>(t, "2000:1:1::0:0:0") == utc(946684800));

  CHECK(error_of(t, "2000:13:01::00:00:00") ==
        "\"2000:13:01::00:00:00\" is not a valid utctime (month 13 is out of range 1..12)");
  CHECK(error_of(t, "2001:02:29::00:00:00") ==
        "\"2001:02:29::00:00:00\" is not a valid utctime (day 29 is out of range 1..28)");
  CHECK(error_of(t, "2000-01-01") ==
        "\"2000-01-01\" is not a valid utctime (YYYY:MM:DD::HH:MM:SS[.ffffff] or now)");
  CHECK(parsed<UtcTime>(t, "2000:02:29::00:00:00").seconds == 951782400);
  CHECK(parsed<UtcTime>(t, "1600:02:29::00:00:00").seconds == -11670998400);
  for (const auto *bad : {"1900:02:29::00:00:00",
                          "2000:00:01::00:00:00",
                          "2000:01:00::00:00:00",
                          "2000:01:32::00:00:00",
                          "2000:04:31::00:00:00",
                          "2000:01:01::24:00:00",
                          "2000:01:01::00:60:00",
                          "2000:01:01::00:00:60",
                          "2000:01:01::00:00:00.",
                          "2000:01:01::00:00:00.1234567",
                          "2000:01:01::00:00:00.12a",
                          "2000:01:01::00:00:00Z",
                          "200:01:01::00:00:00",
                          "2000:001:01::00:00:00",
                          "2000::01::00:00:00",
                          "2000:01:01:00:00:00",
                          "2000:01:01::00:00",
                          "",
                          "Now",
                          "yesterday",
                          "2000:01:01::00:00:00 .5",
                          "+2000:01:01::00:00:00"}) {
    CAPTURE(bad);
    CHECK(rejects(t, bad));
  }
}

TEST_CASE("utctime formatting round-trips", "[property_value]") {
  CHECK(format_scalar(scalar(utc(946684800))) == "2000:01:01::00:00:00.000000");
  CHECK(format_scalar(scalar(utc(-1, 999999))) == "1969:12:31::23:59:59.999999");
  CHECK(format_scalar(scalar(utc(11016LL * 86400 + 45296, 500000))) ==
        "2000:02:29::12:34:56.500000");
  CHECK(format_scalar(scalar(UtcTime{true, 0, 0})) == "now");
  CHECK(format_scalar(scalar(utc(253402300799))) == "9999:12:31::23:59:59.000000");

  // Every 1009th day from year 0 to 9999, at a time of day that moves too.
  const auto t = simple(SimpleType::UtcTime);
  for (std::int64_t days = -719528; days <= 2932896; days += 1009) {
    const auto value = utc(days * 86400 + (days % 86400 + 86400) % 86400, 42);
    const std::string text = format_scalar(scalar(value));
    CAPTURE(days, text);
    const auto back = parse_scalar(t, text);
    REQUIRE(back.has_value());
    CHECK(std::get<UtcTime>(*back) == value);
  }
}

TEST_CASE("complex values", "[property_value]") {
  using C = std::complex<double>;
  SECTION("forms") {
    const auto s = complex_of(SimpleType::Short);
    CHECK(parsed<C>(s, "1+j2") == C(1, 2));
    CHECK(parsed<C>(s, "1-j2") == C(1, -2));
    CHECK(parsed<C>(s, "-1-j2") == C(-1, -2));
    CHECK(parsed<C>(s, "3") == C(3, 0));
    CHECK(parsed<C>(s, "j4") == C(0, 4));
    CHECK(parsed<C>(s, "-j4") == C(0, -4));
    CHECK(parsed<C>(s, "+j4") == C(0, 4));
    CHECK(parsed<C>(s, " 0x10+j0x20 ") == C(16, 32));
    CHECK(parsed<C>(s, "-32768-j32768") == C(-32768, -32768));
  }
  SECTION("integer parts are checked against the base type") {
    const auto s = complex_of(SimpleType::Short);
    CHECK(error_of(s, "1+j70000") == "\"1+j70000\" is not a valid complex short: \"+70000\" is "
                                     "out of range for short (-32768..32767)");
    CHECK(rejects(s, "32768+j0"));
    CHECK(rejects(s, "1.5+j2"));
    CHECK(rejects(s, "1+j2.5"));
    CHECK(rejects(s, "1e2"));
    CHECK(rejects(complex_of(SimpleType::UShort), "1-j2"));
    CHECK(parsed<C>(complex_of(SimpleType::UShort), "65535+j65535") == C(65535, 65535));
    CHECK(rejects(complex_of(SimpleType::Octet), "256"));
    CHECK(parsed<C>(complex_of(SimpleType::ULongLong), "9007199254740992") ==
          C(9007199254740992.0, 0));
    CHECK(error_of(complex_of(SimpleType::ULongLong), "18446744073709551615") ==
          "\"18446744073709551615\" is not a valid complex ulonglong: \"18446744073709551615\" "
          "cannot be held exactly in a complex ulonglong");
    CHECK(rejects(complex_of(SimpleType::LongLong), "9223372036854775807"));
    CHECK(parsed<C>(complex_of(SimpleType::LongLong), "-9223372036854775808") ==
          C(-9223372036854775808.0, 0));
  }
  SECTION("floating parts") {
    const auto f = complex_of(SimpleType::Float);
    CHECK(parsed<C>(f, "1.5e2-j2.5e-1") == C(150, -0.25));
    CHECK(parsed<C>(f, "1e+3+j2") == C(1000, 2));
    CHECK(parsed<C>(f, "0.1") == C(static_cast<double>(0.1F), 0));
    CHECK(parsed<C>(f, "3.402823466e38") ==
          C(static_cast<double>(std::numeric_limits<float>::max()), 0));
    // A part too large for float rounds to infinity, as a plain float does.
    CHECK(std::isinf(parsed<C>(f, "1+j3.5e38").imag()));
    CHECK(parsed<C>(complex_of(SimpleType::Double), "1+j3.5e38") == C(1, 3.5e38));
    CHECK(std::isinf(parsed<C>(complex_of(SimpleType::Double), "1-jinf").imag()));
  }
  SECTION("malformed") {
    const auto d = complex_of(SimpleType::Double);
    CHECK(error_of(d, "1*j2") == "\"1*j2\" is not a valid complex double (a+jb, a-jb, a or jb)");
    for (const auto *bad : {"", "j", "1+j", "1+2", "1 + j2", "1 +j2", "1+ j2", "1+jj2", "1+j2j",
                            "1++j2", "1+j+2", "1+J2", "i2", "1+i2", "--j2", "abc"}) {
      CAPTURE(bad);
      CHECK(rejects(d, bad));
    }
  }
  SECTION("REDHAWK's complexBoolean and complexChar") {
    CHECK(parsed<C>(complex_of(SimpleType::Boolean), "0+j1") == C(0, 1));
    CHECK(parsed<C>(complex_of(SimpleType::Boolean), "true+jfalse") == C(1, 0));
    CHECK(rejects(complex_of(SimpleType::Boolean), "2+j0"));
    CHECK(rejects(complex_of(SimpleType::Boolean), "0-j1"));
    CHECK(parsed<C>(complex_of(SimpleType::Char), "4+j5") == C(4, 5));
    CHECK(parsed<C>(complex_of(SimpleType::Char), "-128+j127") == C(-128, 127));
    CHECK(rejects(complex_of(SimpleType::Char), "128"));
    CHECK(rejects(complex_of(SimpleType::Char), "a"));
  }
  SECTION("non-numeric bases cannot be complex") {
    CHECK(rejects(complex_of(SimpleType::String), "1+j2"));
    CHECK(rejects(complex_of(SimpleType::ObjRef), "x"));
    CHECK(rejects(complex_of(SimpleType::UtcTime), "now"));
  }
}

TEST_CASE("formatting", "[property_value]") {
  CHECK(format_scalar(scalar(true)) == "true");
  CHECK(format_scalar(scalar(false)) == "false");
  CHECK(format_scalar(scalar('x')) == "x");
  CHECK(format_scalar(scalar(std::uint8_t{255})) == "255");
  CHECK(format_scalar(scalar(std::uint8_t{65})) == "65");
  CHECK(format_scalar(scalar(std::int16_t{-32768})) == "-32768");
  CHECK(format_scalar(scalar(std::uint16_t{65535})) == "65535");
  CHECK(format_scalar(scalar(std::int32_t{-7})) == "-7");
  CHECK(format_scalar(scalar(std::uint32_t{4294967295})) == "4294967295");
  CHECK(format_scalar(scalar(INT64_MIN)) == "-9223372036854775808");
  CHECK(format_scalar(scalar(UINT64_MAX)) == "18446744073709551615");
  CHECK(format_scalar(scalar(std::numeric_limits<float>::max())) == "3.4028235e+38");
  CHECK(format_scalar(scalar(0.1F)) == "0.1");
  CHECK(format_scalar(scalar(0.1)) == "0.1");
  CHECK(format_scalar(scalar(1e300)) == "1e+300");
  CHECK(format_scalar(scalar(-std::numeric_limits<double>::infinity())) == "-inf");
  CHECK(format_scalar(scalar(std::string(" a b "))) == " a b ");
  CHECK(format_scalar(scalar(std::complex<double>(1, 2))) == "1+j2");
  CHECK(format_scalar(scalar(std::complex<double>(1, -2))) == "1-j2");
  CHECK(format_scalar(scalar(std::complex<double>(-0.5, 0.25))) == "-0.5+j0.25");
  CHECK(format_scalar(scalar(std::complex<double>(1e18, 0))) == "1000000000000000000+j0");
  CHECK(format_scalar(scalar(std::complex<double>(1e300, -1e-300))) == "1e+300-j1e-300");
}

TEST_CASE("parse then format then parse gives the same value", "[property_value]") {
  const std::vector<std::pair<TypeSpec, std::string_view>> cases{
      {simple(SimpleType::Boolean), "TRUE"},
      {simple(SimpleType::Char), " "},
      {simple(SimpleType::Octet), "0xfe"},
      {simple(SimpleType::Short), "-32768"},
      {simple(SimpleType::UShort), "65535"},
      {simple(SimpleType::Long), "-0x80000000"},
      {simple(SimpleType::ULong), "4294967295"},
      {simple(SimpleType::LongLong), "-9223372036854775808"},
      {simple(SimpleType::ULongLong), "18446744073709551615"},
      {simple(SimpleType::Float), "3.402823466e38"},
      {simple(SimpleType::Float), "0.1"},
      {simple(SimpleType::Float), "1e-45"},
      {simple(SimpleType::Float), "-inf"},
      {simple(SimpleType::Double), "2.2250738585072014e-308"},
      {simple(SimpleType::Double), "0.30000000000000004"},
      {simple(SimpleType::String), " x "},
      {simple(SimpleType::ObjRef), "IOR:00"},
      {simple(SimpleType::UtcTime), "2000:02:29::12:34:56.5"},
      {simple(SimpleType::UtcTime), "now"},
      {complex_of(SimpleType::Short), "-32768-j32767"},
      {complex_of(SimpleType::ULongLong), "9007199254740992+j1"},
      {complex_of(SimpleType::LongLong), "-9223372036854775808"},
      {complex_of(SimpleType::Float), "0.1-j3.402823466e38"},
      {complex_of(SimpleType::Double), "1e-300+j1e300"},
  };
  for (const auto &[spec, text] : cases) {
    CAPTURE(to_string(spec.type), spec.complex, text);
    const auto first = parse_scalar(spec, text);
    REQUIRE(first.has_value());
    const std::string printed = format_scalar(*first);
    CAPTURE(printed);
    const auto second = parse_scalar(spec, printed);
    REQUIRE(second.has_value());
    CHECK(*second == *first);
  }
}

TEST_CASE("satisfies: the device's value is on the left", "[property_value]") {
  const auto i = [](std::int32_t v) { return scalar(v); };
  SECTION("orders on numbers") {
    CHECK(satisfies(Action::Eq, i(5), i(5)) == true);
    CHECK(satisfies(Action::Eq, i(5), i(6)) == false);
    CHECK(satisfies(Action::Ne, i(5), i(6)) == true);
    CHECK(satisfies(Action::Ne, i(5), i(5)) == false);
    CHECK(satisfies(Action::Gt, i(6), i(5)) == true);
    CHECK(satisfies(Action::Gt, i(5), i(5)) == false);
    CHECK(satisfies(Action::Gt, i(4), i(5)) == false);
    CHECK(satisfies(Action::Lt, i(4), i(5)) == true);
    CHECK(satisfies(Action::Lt, i(5), i(5)) == false);
    CHECK(satisfies(Action::Ge, i(5), i(5)) == true);
    CHECK(satisfies(Action::Ge, i(4), i(5)) == false);
    CHECK(satisfies(Action::Le, i(5), i(5)) == true);
    CHECK(satisfies(Action::Le, i(6), i(5)) == false);
    CHECK(satisfies(Action::Gt, scalar(std::uint8_t{200}), scalar(std::uint8_t{100})) == true);
    CHECK(satisfies(Action::Lt, scalar(UINT64_MAX), scalar(std::uint64_t{1})) == false);
    CHECK(satisfies(Action::Ge, scalar(2.5F), scalar(2.5F)) == true);
    CHECK(satisfies(Action::Lt, scalar(-1.0), scalar(0.0)) == true);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    CHECK(satisfies(Action::Eq, scalar(nan), scalar(nan)) == false);
    CHECK(satisfies(Action::Gt, scalar(nan), scalar(0.0)) == false);
  }
  SECTION("equality only on non-numeric types") {
    const auto str = [](const char *v) { return scalar(std::string(v)); };
    CHECK(satisfies(Action::Eq, str("x86_64"), str("x86_64")) == true);
    CHECK(satisfies(Action::Ne, str("x86_64"), str("arm")) == true);
    CHECK(satisfies(Action::Gt, str("b"), str("a")) == std::nullopt);
    CHECK(satisfies(Action::Eq, scalar(true), scalar(true)) == true);
    CHECK(satisfies(Action::Ne, scalar(true), scalar(false)) == true);
    CHECK(satisfies(Action::Ge, scalar(true), scalar(false)) == std::nullopt);
    CHECK(satisfies(Action::Eq, scalar('a'), scalar('a')) == true);
    CHECK(satisfies(Action::Lt, scalar('a'), scalar('b')) == std::nullopt);
    CHECK(satisfies(Action::Eq, scalar(utc(5)), scalar(utc(5))) == true);
    CHECK(satisfies(Action::Ne, scalar(utc(5)), scalar(utc(5, 1))) == true);
    CHECK(satisfies(Action::Gt, scalar(utc(6)), scalar(utc(5))) == std::nullopt);
    const auto c = [](double re, double im) { return scalar(std::complex<double>(re, im)); };
    CHECK(satisfies(Action::Eq, c(1, 2), c(1, 2)) == true);
    CHECK(satisfies(Action::Ne, c(1, 2), c(1, -2)) == true);
    CHECK(satisfies(Action::Le, c(1, 2), c(1, 2)) == std::nullopt);
  }
  SECTION("external and mismatched types give no answer") {
    CHECK(satisfies(Action::External, i(5), i(5)) == std::nullopt);
    CHECK(satisfies(Action::External, scalar(std::string("a")), scalar(std::string("a"))) ==
          std::nullopt);
    CHECK(satisfies(Action::Eq, i(5), scalar(std::int64_t{5})) == std::nullopt);
    CHECK(satisfies(Action::Gt, scalar(5.0F), scalar(4.0)) == std::nullopt);
    CHECK(satisfies(Action::Eq, scalar(std::string("1")), i(1)) == std::nullopt);
  }
}
