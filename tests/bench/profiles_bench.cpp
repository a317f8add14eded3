// Parse + validate + resolve time of domain profiles: the whole REDHAWK corpus, one application,
// and one file, each with a fresh ProfileLoader (cold file cache) while the XML reader stays
// loaded (its compiled schemas too); and the cold start of the XML reader itself (loading the
// module and Xerces, compiling the schemas), which a process pays once per burst of reading.
#include <algorithm>
#include <filesystem>
#include <vector>

#include <benchmark/benchmark.h>

#include "profile/profile_loader.hpp"
#include "profile/xml_reader.hpp"

namespace {

namespace fs = std::filesystem;
using rsca::profile::ProfileLoader;

// Keeps the XML reader loaded for a benchmark's whole run.
std::shared_ptr<rsca::profile::XmlReader> hold_reader(benchmark::State &state) {
  auto reader = rsca::profile::XmlReader::acquire();
  if (!reader) {
    state.SkipWithError("the XML reader module did not load");
    return nullptr;
  }
  return *reader;
}

std::vector<fs::path> corpus_files() {
  std::vector<fs::path> files;
  for (const auto &e : fs::recursive_directory_iterator(RSCA_CORPUS_DIR))
    if (e.is_regular_file() && e.path().extension() == ".xml")
      files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

void BM_ValidateWholeCorpus(benchmark::State &state) {
  const auto files = corpus_files();
  const auto reader = hold_reader(state);
  for (auto _ : state) {
    ProfileLoader loader;
    std::size_t valid = 0;
    for (const auto &f : files)
      valid += loader.validate(f).has_value() ? 1 : 0;
    if (valid != files.size())
      state.SkipWithError("a corpus file did not validate");
    benchmark::DoNotOptimize(valid);
  }
  state.counters["files"] = static_cast<double>(files.size());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(files.size()));
}
BENCHMARK(BM_ValidateWholeCorpus)->Unit(benchmark::kMillisecond);

void BM_LoadApplication(benchmark::State &state) {
  const auto reader = hold_reader(state);
  const fs::path sad =
      fs::path(RSCA_CORPUS_DIR) / "dom/waveforms/rh/FM_RBDS_demo/FM_RBDS_demo.sad.xml";
  for (auto _ : state) {
    ProfileLoader loader;
    auto app = loader.load_application(sad);
    if (!app)
      state.SkipWithError("FM_RBDS_demo did not load");
    benchmark::DoNotOptimize(app);
  }
}
BENCHMARK(BM_LoadApplication)->Unit(benchmark::kMicrosecond);

void BM_ReadLargestPrf(benchmark::State &state) {
  const auto reader = hold_reader(state);
  const fs::path prf = fs::path(RSCA_CORPUS_DIR) / "dev/devices/rh/MSDD/MSDD.prf.xml";
  for (auto _ : state) {
    auto d = rsca::profile::read_descriptor(prf);
    if (!d)
      state.SkipWithError("MSDD.prf.xml did not read");
    benchmark::DoNotOptimize(d);
  }
  state.SetBytesProcessed(state.iterations() * static_cast<std::int64_t>(fs::file_size(prf)));
}
BENCHMARK(BM_ReadLargestPrf)->Unit(benchmark::kMicrosecond);

// One small profile with nothing loaded before: what a component pays at start.
void BM_ColdStartOneProfile(benchmark::State &state) {
  const fs::path spd =
      fs::path(RSCA_SOURCE_DIR) / "profiles/dom/components/Producer/Producer.spd.xml";
  for (auto _ : state) {
    auto pkg = ProfileLoader().load_softpkg(spd);
    if (!pkg)
      state.SkipWithError("Producer.spd.xml did not load");
    benchmark::DoNotOptimize(pkg);
  }
}
BENCHMARK(BM_ColdStartOneProfile)->Unit(benchmark::kMillisecond);

} // namespace

BENCHMARK_MAIN();
