#include "protocol/node_link.hpp"

#include <array>

namespace rsca::protocol::link {

namespace {

// The key that names each kind of frame, in the variant's order.
constexpr std::array<std::string_view, std::variant_size_v<Frame>> kKinds{
    "request", "reply", "announce", "withdraw", "route"};

template <std::size_t I = 0>
tl::expected<Frame, std::string> decode_kind(std::string_view kind, const Json &value) {
  if constexpr (I == std::variant_size_v<Frame>) {
    return tl::unexpected(fmt::format("unknown frame kind \"{}\"", kind));
  } else {
    if (kind != kKinds[I])
      return decode_kind<I + 1>(kind, value);
    using Message = std::variant_alternative_t<I, Frame>;
    auto message = decode<Message>(value);
    if (!message)
      return tl::unexpected(fmt::format("{} frame: {}", kind, message.error()));
    return Frame(std::in_place_index<I>, std::move(*message));
  }
}

} // namespace

Json encode_frame(const Frame &frame) {
  return std::visit(
      [&frame](const auto &message) {
        return Json{{std::string(kKinds[frame.index()]), encode(message)}};
      },
      frame);
}

tl::expected<Frame, std::string> decode_frame(const Json &json) {
  if (!json.is_object() || json.size() != 1)
    return tl::unexpected(std::string("a frame is an object with exactly one key, its kind"));
  const auto only = json.begin();
  return decode_kind(only.key(), only.value());
}

} // namespace rsca::protocol::link
