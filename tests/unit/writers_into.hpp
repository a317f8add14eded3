// A look at the control plane's writers as DDS's built-in publication topic shows them, for the
// tests of endpoints and their ways.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <catch2/catch.hpp>
#include <dds/dds.h>

#include "dds/participant.hpp"

namespace rsca::test {

// How many writers of this participant's control plane write `topic` into `partition` (an
// address), as DDS's built-in publication topic shows them.
inline int writers_into(const std::shared_ptr<dds::Participant> &pp, const char *topic,
                        const std::string &partition) {
  const dds_entity_t reader =
      dds_create_reader(pp->get(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  REQUIRE(reader > 0);
  void *samples[256] = {nullptr};
  dds_sample_info_t infos[256];
  const dds_return_t n = dds_read(reader, samples, infos, 256, 256);
  int count = 0;
  for (dds_return_t i = 0; i < n; ++i) {
    const auto *w = static_cast<const dds_builtintopic_endpoint_t *>(samples[i]);
    uint32_t names = 0;
    char **parts = nullptr;
    if (!infos[i].valid_data || std::string(w->topic_name) != topic ||
        !dds_qget_partition(w->qos, &names, &parts))
      continue;
    for (uint32_t k = 0; k < names; ++k) {
      count += partition == parts[k] ? 1 : 0;
      dds_free(parts[k]);
    }
    dds_free(parts);
  }
  if (n > 0)
    dds_return_loan(reader, samples, n);
  dds_delete(reader);
  return count;
}

} // namespace rsca::test
