// Properties from the CLI (issue 39, item 6): an application's external properties configured and
// queried under the application's name, reaching the component the SAD maps them to; and struct
// and sequence properties written in the CLI's syntax (`rsca configure --help`).
#include <filesystem>

#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include "domain_fixture.hpp"

using namespace rsca::test;
using rsca::control::Json;

namespace {

// A property of one component, as app.query answers it.
Json queried_property(TestDomain &domain, const std::string &app, const std::string &component,
                      const std::string &id) {
  auto q = domain.call("app.query",
                       Json{{"app", app}, {"component", component}, {"ids", Json::array({id})}});
  INFO((q ? q->dump() : q.error().message));
  REQUIRE(q.has_value());
  return q->at("properties").at(id);
}

// What the CLI printed, having checked that it exited `rc`.
std::string property_cli(TestDomain &domain, int rc, const std::vector<std::string> &args) {
  auto [got, out] = domain.cli(args);
  INFO(fmt::format("{}: {}", fmt::join(args, " "), out));
  CHECK(got == rc);
  return out;
}

} // namespace

TEST_CASE("configure APP with an external property's id sets the component the SAD maps it to, "
          "says which, and query APP shows it under that id",
          "[integration][properties]") {
  TestDomain domain;
  domain.launch_shipped("ProducerConsumer");

  CHECK_THAT(property_cli(domain, 0, {"configure", "ProducerConsumer", "producer_rate_hz=10"}),
             Catch::Contains("set producer_rate_hz (Producer_1:rate_hz) = 10"));
  CHECK(queried_property(domain, "ProducerConsumer", "Producer_1", "rate_hz").get<double>() ==
        10.0);

  // Any other id is the assembly controller's (Consumer_1), and the reply says so.
  const Json set =
      Json::parse(
          property_cli(domain, 0, {"--json", "configure", "ProducerConsumer", "log_every=7"}))
          .at("set");
  REQUIRE(set.size() == 1);
  CHECK(set[0].at("component") == "Consumer_1");
  CHECK(set[0].at("property") == "log_every");
  CHECK(set[0].at("value") == 7);

  // Another component by its own word, as APP/COMPONENT.
  CHECK_THAT(
      property_cli(domain, 0, {"configure", "ProducerConsumer", "Producer_1", "payload_size=32"}),
      Catch::Contains("set payload_size (Producer_1:payload_size) = 32"));

  // Query under the application's name: the external property under its external id, beside
  // the assembly controller's own.
  const Json all = Json::parse(property_cli(domain, 0, {"--json", "query", "ProducerConsumer"}))
                       .at("properties");
  CHECK(all.at("producer_rate_hz").get<double>() == 10.0);
  CHECK(all.at("log_every") == 7);
  CHECK_THAT(property_cli(domain, 0, {"query", "ProducerConsumer", "producer_rate_hz"}),
             Catch::Contains("producer_rate_hz = 10"));

  // A bad value is refused and nothing is applied; an id nobody has says where it looked.
  CHECK_THAT(property_cli(domain, 1, {"configure", "ProducerConsumer", "producer_rate_hz=1e9"}),
             Catch::Contains("outside its range"));
  CHECK(queried_property(domain, "ProducerConsumer", "Producer_1", "rate_hz").get<double>() ==
        10.0);
  CHECK_THAT(property_cli(domain, 3, {"configure", "ProducerConsumer", "no_such_thing=1"}),
             Catch::Contains("has no external property no_such_thing"));
}

TEST_CASE("struct, sequence and struct sequence properties set from the CLI's syntax",
          "[integration][properties]") {
  TestDomain domain;
  domain.create("Healthy");

  auto configure = [&](const std::string &component, const std::string &assignment) {
    return property_cli(domain, 0, {"configure", "Healthy/" + component, assignment});
  };
  configure("Victim_1", "gains=[0.5,2,3]");
  CHECK(queried_property(domain, "Healthy", "Victim_1", "gains") == Json::array({0.5, 2.0, 3.0}));
  configure("Victim_1", "gains=4,5"); // the bare form stays
  CHECK(queried_property(domain, "Healthy", "Victim_1", "gains") == Json::array({4.0, 5.0}));
  configure("Victim_1", "gains=[]");
  CHECK(queried_property(domain, "Healthy", "Victim_1", "gains") == Json::array());

  configure("Producer_1", "stream={stream_id=s1, sample_rate=500}");
  const Json stream = queried_property(domain, "Healthy", "Producer_1", "stream");
  CHECK(stream.at("stream_id") == "s1");
  CHECK(stream.at("sample_rate").get<double>() == 500.0);
  configure("Producer_1", R"(stream=json:{"stream_id": "j", "sample_rate": 250})");
  CHECK(queried_property(domain, "Healthy", "Producer_1", "stream").at("stream_id") == "j");

  configure("Victim_1", "limits=[{limit::name=arm,limit::max=1.5,limit::steps=[1,2]},"
                        "{limit::name=\"b, c\",limit::max=2,limit::steps=[]}]");
  const Json limits = queried_property(domain, "Healthy", "Victim_1", "limits");
  INFO(limits.dump());
  REQUIRE(limits.size() == 2);
  CHECK(limits[0].at("limit::name") == "arm");
  CHECK(limits[0].at("limit::max").get<double>() == 1.5);
  CHECK(limits[0].at("limit::steps") == Json::array({1, 2}));
  CHECK(limits[1].at("limit::name") == "b, c");

  // Malformed text is refused, naming the property, and nothing is applied.
  const std::pair<const char *, const char *> malformed[] = {{"Victim_1", "gains=[1,2"},
                                                             {"Victim_1", "gains=[1,x]"},
                                                             {"Producer_1", "stream=s1"},
                                                             {"Victim_1", "limits=[{limit::max}]"}};
  for (const auto &[component, bad] : malformed) {
    const std::string text(bad);
    CHECK_THAT(property_cli(domain, 1, {"configure", fmt::format("Healthy/{}", component), text}),
               Catch::Contains(fmt::format("\"{}\"", text.substr(0, text.find('=')))));
  }
  CHECK(queried_property(domain, "Healthy", "Victim_1", "gains") == Json::array());
  CHECK(queried_property(domain, "Healthy", "Victim_1", "limits").size() == 2);
  CHECK(queried_property(domain, "Healthy", "Producer_1", "stream").at("stream_id") == "j");
}

namespace {

// A folder made for a test in the working folder, removed when it ends (if the test made it).
struct ShowNameFolder {
  std::filesystem::path path;
  bool made = false;
  explicit ShowNameFolder(std::filesystem::path where) : path(std::move(where)) {
    std::error_code ec;
    made = std::filesystem::create_directory(path, ec);
  }
  ~ShowNameFolder() {
    std::error_code ec;
    if (made)
      std::filesystem::remove(path, ec);
  }
  ShowNameFolder(const ShowNameFolder &) = delete;
  ShowNameFolder &operator=(const ShowNameFolder &) = delete;
};

} // namespace

TEST_CASE("rsca show NAME shows the running application NAME, not a folder NAME in the working "
          "folder, and says which it showed",
          "[integration][cli]") {
  TestDomain domain;
  domain.launch_shipped("ProducerConsumer");
  const ShowNameFolder folder(std::filesystem::current_path() / "ProducerConsumer");
  REQUIRE(std::filesystem::is_directory(folder.path));
  const std::string out = property_cli(domain, 0, {"show", "ProducerConsumer"});
  CHECK_THAT(out, Catch::Contains("application ProducerConsumer"));
  CHECK_THAT(out, Catch::Contains("Producer_1"));
  CHECK_THAT(out, Catch::Contains("not the folder ProducerConsumer here"));
}
