#include "component/sample_view.hpp"

#include "component/port_wire.hpp"

namespace rsca::component {

namespace {

constexpr std::uint32_t kViewBatch = 32;

nlohmann::json json_of(const port::Samples &v) {
  return {{"timestamp_ns", v.timestamp_ns},
          {"sequence", v.sequence},
          {"stream_id", v.stream_id},
          {"sample_rate", v.sample_rate},
          {"complex", v.complex},
          {"end_of_stream", v.end_of_stream},
          {"samples", v.samples}};
}

nlohmann::json json_of(const port::PropertyEvent &v) {
  auto value = nlohmann::json::parse(v.value, nullptr, /*allow_exceptions=*/false);
  return {{"timestamp_ns", v.timestamp_ns},
          {"source", v.source},
          {"id", v.id},
          {"value", value.is_discarded() ? nlohmann::json(v.value) : std::move(value)}};
}

nlohmann::json json_of(const port::Command &v) {
  return {{"timestamp_ns", v.timestamp_ns},
          {"sequence", v.sequence},
          {"source", v.source},
          {"name", v.name},
          {"args", v.args},
          {"text", v.text}};
}

template <typename T>
class SampleViewOf final : public SampleView {
public:
  const dds_topic_descriptor_t *descriptor() const override {
    return port::wire::Traits<T>::descriptor();
  }

  std::vector<nlohmann::json> take(dds_entity_t reader, std::size_t most) override {
    using Wire = typename port::wire::Traits<T>::C;
    std::vector<nlohmann::json> out;
    while (out.size() < most) {
      void *samples[kViewBatch] = {nullptr};
      dds_sample_info_t infos[kViewBatch];
      const dds_return_t n = dds_take(reader, samples, infos, kViewBatch, kViewBatch);
      if (n <= 0)
        break;
      for (dds_return_t i = 0; i < n; ++i) {
        if (!infos[i].valid_data || out.size() >= most)
          continue;
        port::wire::from_wire(*static_cast<const Wire *>(samples[i]), value_);
        out.push_back(json_of(value_));
      }
      dds_return_loan(reader, samples, n);
      if (static_cast<std::uint32_t>(n) < kViewBatch)
        break;
    }
    return out;
  }

private:
  T value_; // reused from sample to sample
};

} // namespace

std::unique_ptr<SampleView> SampleView::of(port::PortType type) {
  return port::wire::make_for<SampleView, SampleViewOf>(type);
}

} // namespace rsca::component
