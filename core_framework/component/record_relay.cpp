#include "component/record_relay.hpp"

#include <spdlog/spdlog.h>

#include "component/port_record.hpp"
#include "component/port_wire.hpp"

namespace rsca::component {

namespace {

constexpr std::uint32_t kRelayBatch = 32;

template <typename T>
class RecordRelayOf final : public RecordRelay {
public:
  const dds_topic_descriptor_t *descriptor() const override {
    return port::wire::Traits<T>::descriptor();
  }

  std::size_t to_dds(shm::RingReader &ring, dds_entity_t writer) override {
    return ring.take(
        [this](const std::byte *at, std::size_t bytes) {
          port::record::Reader r(at, bytes);
          return port::record::read(r, value_);
        },
        [this, writer] {
          const auto wire = port::wire::to_wire(value_);
          if (const dds_return_t rc = dds_write(writer, &wire); rc < 0)
            note_failure("relay to DDS: a write failed", dds_strretcode(rc));
        });
  }

  std::size_t from_dds(dds_entity_t reader, dds_instance_handle_t own,
                       shm::RingWriter &ring) override {
    using Wire = typename port::wire::Traits<T>::C;
    std::size_t relayed = 0;
    for (;;) {
      void *samples[kRelayBatch] = {nullptr};
      dds_sample_info_t infos[kRelayBatch];
      const dds_return_t n = dds_take(reader, samples, infos, kRelayBatch, kRelayBatch);
      if (n <= 0)
        return relayed;
      for (dds_return_t i = 0; i < n; ++i) {
        if (!infos[i].valid_data || infos[i].publication_handle == own)
          continue;
        port::wire::from_wire(*static_cast<const Wire *>(samples[i]), value_);
        auto written = ring.write(port::record::size_of(value_), [this](std::byte *at) {
          port::record::Writer w(at);
          port::record::write(value_, w);
        });
        if (written)
          ++relayed;
        else
          note_failure("relay from DDS: a sample is dropped", written.error());
      }
      dds_return_loan(reader, samples, n);
      if (static_cast<std::uint32_t>(n) < kRelayBatch)
        return relayed;
    }
  }

private:
  // A failure that repeats with every sample (one too large for the ring) is logged at its 1st,
  // 2nd, 4th, 8th... occurrence, with the count: the log says it goes on without flooding.
  void note_failure(const char *what, const std::string &why) {
    const std::uint64_t n = ++failures_;
    if ((n & (n - 1)) == 0)
      spdlog::warn("{}: {} ({} so far)", what, why, n);
  }

  T value_; // reused from sample to sample: its buffers keep their capacity
  std::uint64_t failures_ = 0;
};

} // namespace

std::unique_ptr<RecordRelay> RecordRelay::of(port::PortType type) {
  return port::wire::make_for<RecordRelay, RecordRelayOf>(type);
}

} // namespace rsca::component
