#include "node/process_logs.hpp"

#include <algorithm>
#include <fstream>

#include <fmt/format.h>

#include "common/names.hpp"

namespace rsca::node {
namespace {

namespace fs = std::filesystem;
namespace op = protocol::node;
using control::CallResult;
using protocol::Status;

// The log of the process named: the running process's own, a hosted component's host's (by
// pid), or the file a process of that name left in the folder; empty when there is none.
fs::path log_of(const fs::path &log_dir, const op::LogsRequest &request,
                const std::vector<op::ProcessRecord> &running) {
  const auto label = op::process_label(request.application, request.component);
  for (const auto &p : running)
    if (p.label == label)
      return p.log;
  if (request.pid)
    for (const auto &p : running)
      if (p.pid == *request.pid && op::split_process_label(p.label).first == request.application)
        return p.log;
  auto file = log_dir / request.application / (request.component + ".log");
  std::error_code ec;
  return fs::is_regular_file(file, ec) ? file : fs::path();
}

struct Span {
  std::uint64_t from = 0;
  std::uint64_t to = 0;
};

// The bytes to read of a log of `size` bytes: from the offset asked (from 0 when the log is now
// shorter), else its last `max`.
Span span_of(const op::LogsRequest &request, std::uint64_t size, std::uint64_t max) {
  if (request.offset) {
    const std::uint64_t from = *request.offset <= size ? *request.offset : 0;
    return {from, std::min(size, from + max)};
  }
  return {size > max ? size - max : 0, size};
}

// Whole lines only: a tail starts after its first newline (unless it is the log's start), and
// any piece ends at its last one (unless it has none), so a line is never shown in two halves.
Span whole_lines(const std::string &bytes, Span span, bool tail) {
  std::size_t begin = 0;
  if (tail && span.from > 0)
    if (auto nl = bytes.find('\n'); nl != std::string::npos)
      begin = nl + 1;
  std::size_t end = bytes.size();
  if (auto nl = bytes.rfind('\n'); nl != std::string::npos && nl + 1 > begin)
    end = nl + 1;
  return {span.from + begin, span.from + end};
}

} // namespace

std::string utf8_or_replaced(std::string_view bytes) {
  std::string out;
  out.reserve(bytes.size());
  std::size_t i = 0;
  while (i < bytes.size()) {
    const auto c = static_cast<unsigned char>(bytes[i]);
    const std::size_t length = c < 0x80            ? 1
                               : (c >> 5U) == 0x6  ? 2
                               : (c >> 4U) == 0xE  ? 3
                               : (c >> 3U) == 0x1E ? 4
                                                   : 0;
    bool valid = length != 0 && i + length <= bytes.size();
    for (std::size_t k = 1; valid && k < length; ++k)
      valid = (static_cast<unsigned char>(bytes[i + k]) >> 6U) == 0x2;
    // Overlong forms and surrogates are invalid too (nlohmann::json refuses them when it writes).
    if (valid && length == 2)
      valid = c >= 0xC2;
    if (valid && length >= 3) {
      const auto d = static_cast<unsigned char>(bytes[i + 1]);
      valid = !(c == 0xE0 && d < 0xA0) && !(c == 0xED && d >= 0xA0) && !(c == 0xF0 && d < 0x90) &&
              !(c == 0xF4 && d >= 0x90) && c <= 0xF4;
    }
    if (!valid) {
      out += "\xEF\xBF\xBD";
      ++i;
      continue;
    }
    out.append(bytes.substr(i, length));
    i += length;
  }
  return out;
}

CallResult<op::LogsReply> read_log(const fs::path &log_dir, const op::LogsRequest &request,
                                   const std::vector<op::ProcessRecord> &running) {
  for (const auto &[what, name] : {std::pair{"the application", &request.application},
                                   std::pair{"the component", &request.component}})
    if (auto ok = check_name(what, *name); !ok)
      return protocol::call_error(Status::BadRequest, ok.error());
  const fs::path file = log_of(log_dir, request, running);
  const auto what = op::process_label(request.application, request.component);
  if (file.empty())
    return protocol::call_error(Status::NotFound, fmt::format("no log of {} here", what));
  std::ifstream in(file, std::ios::binary);
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (!in || ec)
    return protocol::call_error(Status::Failed, fmt::format("the log of {} cannot be read", what));
  const auto max = std::clamp<std::uint64_t>(
      request.max_bytes.value_or(op::LogsRequest::kDefaultBytes), 1, op::LogsRequest::kMaxBytes);
  const Span span = span_of(request, size, max);
  std::string bytes(span.to - span.from, '\0');
  in.seekg(static_cast<std::streamoff>(span.from));
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  const Span lines = whole_lines(bytes, {span.from, span.from + bytes.size()}, !request.offset);
  const auto text = std::string_view(bytes).substr(lines.from - span.from, lines.to - lines.from);
  return op::LogsReply{file.lexically_relative(log_dir).string(), lines.from, lines.to,
                       utf8_or_replaced(text)};
}

} // namespace rsca::node
