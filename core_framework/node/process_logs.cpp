#include "node/process_logs.hpp"

#include <algorithm>
#include <fstream>
#include <optional>

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

// Whole lines only: a tail starts after its first newline (unless it is the log's start), and
// any piece ends at its last one (unless it has none), so a line is never shown in two halves.
Span whole_lines(const std::string &bytes, bool tail_from_inside) {
  std::size_t begin = 0;
  if (tail_from_inside)
    if (auto nl = bytes.find('\n'); nl != std::string::npos)
      begin = nl + 1;
  std::size_t end = bytes.size();
  if (auto nl = bytes.rfind('\n'); nl != std::string::npos && nl + 1 > begin)
    end = nl + 1;
  return {begin, end};
}

std::uint64_t size_of(const fs::path &file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  return ec ? 0 : size;
}

// Bytes [from, to) of `file`, or fewer where it ends.
std::string bytes_of(const fs::path &file, Span span) {
  if (span.to <= span.from)
    return {};
  std::ifstream in(file, std::ios::binary);
  std::string bytes(span.to - span.from, '\0');
  in.seekg(static_cast<std::streamoff>(span.from));
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return bytes;
}

// What a read takes before it is cut to whole lines: bytes that end at `end` in the log and
// start at `start` in it (nothing: they begin in LOG.1), and whether they start inside the text
// (a tail's, whose first line is partial).
struct Piece {
  std::string bytes;
  std::optional<std::uint64_t> start;
  std::uint64_t end = 0;
  bool from_inside = false;
};

// The last `max` bytes, reaching into LOG.1 when the log holds fewer.
Piece tail_of(const LogFiles &files, std::uint64_t size, std::uint64_t max) {
  const auto &[log, previous] = files;
  if (size >= max)
    return {bytes_of(log, {size - max, size}), size - max, size, size > max};
  const auto before = size_of(previous);
  const auto wanted = std::min(before, max - size);
  if (wanted == 0)
    return {bytes_of(log, {0, size}), 0, size, false};
  return {bytes_of(previous, {before - wanted, before}) + bytes_of(log, {0, size}), std::nullopt,
          size, wanted < before};
}

// From `offset` on: in the log; past its end (it was rotated since), the rest of LOG.1 from there
// and then the log from its start, at most half of `max` each when both are longer.
Piece from_offset(const LogFiles &files, std::uint64_t size, std::uint64_t offset,
                  std::uint64_t max) {
  const auto &[log, previous] = files;
  if (offset <= size) {
    const auto end = std::min(size, offset + max);
    return {bytes_of(log, {offset, end}), offset, end, false};
  }
  const auto before = size_of(previous);
  if (offset >= before) { // truncated, not rotated: nothing of LOG.1 is new
    const auto end = std::min(size, max);
    return {bytes_of(log, {0, end}), 0, end, false};
  }
  const auto end = std::min(size, std::max(max / 2, max - std::min(before - offset, max)));
  const auto rest = std::min(before - offset, max - end);
  return {bytes_of(previous, {before - rest, before}) + bytes_of(log, {0, end}), std::nullopt, end,
          rest < before - offset};
}

} // namespace

fs::path previous_of(const fs::path &log) {
  return fs::path(log.string() + ".1");
}

Expected<bool> rotate_if_over(const fs::path &log, std::uint64_t max_bytes) {
  if (max_bytes == 0 || size_of(log) <= max_bytes)
    return false;
  std::error_code ec;
  fs::copy_file(log, previous_of(log), fs::copy_options::overwrite_existing, ec);
  if (!ec)
    fs::resize_file(log, 0, ec);
  if (ec)
    return make_error({log.string(), 0, 0}, "io", fmt::format("cannot rotate: {}", ec.message()));
  return true;
}

std::size_t sweep_logs(const fs::path &log_dir, const std::vector<op::ProcessRecord> &running,
                       std::chrono::seconds keep) {
  std::vector<fs::path> written;
  for (const auto &p : running) {
    written.push_back(fs::path(p.log).lexically_normal());
    written.push_back(previous_of(written.back()));
  }
  const auto before = fs::file_time_type::clock::now() - keep;
  std::size_t deleted = 0;
  std::error_code ec;
  for (const auto &folder : fs::directory_iterator(log_dir, ec)) {
    std::error_code fec;
    if (!folder.is_directory(fec) || folder.is_symlink(fec))
      continue;
    bool empty = true;
    for (const auto &file : fs::directory_iterator(folder.path(), fec)) {
      std::error_code e;
      const bool old = file.is_regular_file(e) && file.last_write_time(e) < before && !e;
      const auto path = file.path().lexically_normal();
      if (!old || std::find(written.begin(), written.end(), path) != written.end() ||
          !fs::remove(file.path(), e)) {
        empty = false;
        continue;
      }
      ++deleted;
    }
    if (empty && !fec)
      fs::remove(folder.path(), fec); // only an empty folder goes
  }
  return deleted;
}

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

std::string log_tail(const fs::path &log, std::uint64_t from, std::size_t max_lines,
                     std::size_t max_bytes) {
  const auto size = size_of(log);
  const std::uint64_t begun = from <= size ? from : 0;
  const std::uint64_t start =
      std::max<std::uint64_t>(begun, size > max_bytes ? size - max_bytes : 0);
  std::string bytes = bytes_of(log, {start, size});
  // Begun inside a line: from the next one, unless that line is the last (cut below).
  if (const auto nl = bytes.find('\n');
      start > begun && nl != std::string::npos && nl + 1 < bytes.size())
    bytes.erase(0, nl + 1);
  std::string text = utf8_or_replaced(bytes);
  if (!text.empty() && text.back() != '\n')
    text += '\n';
  // Replaced bytes grow by up to three times: lines are dropped from the front until both
  // bounds hold (a single line longer than max_bytes is cut from its start, whole characters).
  std::size_t kept = text.size();
  for (std::size_t lines = 0; kept > 0 && lines < max_lines; ++lines) {
    const auto nl = kept >= 2 ? text.rfind('\n', kept - 2) : std::string::npos;
    const std::size_t begin = nl == std::string::npos ? 0 : nl + 1;
    if (text.size() - begin > max_bytes)
      break;
    kept = begin;
  }
  if (kept == text.size() && !text.empty()) { // the last line alone is too long
    kept = text.size() - std::min(text.size(), max_bytes);
    while (kept < text.size() && (static_cast<unsigned char>(text[kept]) & 0xC0U) == 0x80U)
      ++kept;
  }
  return text.substr(kept);
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
  return read_piece({file, previous_of(file)}, log_dir, request.offset, request.max_bytes, what);
}

CallResult<op::LogsReply> read_piece(const LogFiles &files, const fs::path &log_dir,
                                     std::optional<std::uint64_t> offset,
                                     std::optional<std::uint64_t> max_bytes,
                                     const std::string &what) {
  const fs::path &file = files.log;
  std::error_code ec;
  if (!fs::is_regular_file(file, ec))
    return protocol::call_error(Status::Failed, fmt::format("the log of {} cannot be read", what));
  const auto max = std::clamp<std::uint64_t>(max_bytes.value_or(op::LogsRequest::kDefaultBytes), 1,
                                             op::LogsRequest::kMaxBytes);
  const auto size = size_of(file);
  const Piece piece = offset ? from_offset(files, size, *offset, max) : tail_of(files, size, max);
  const Span lines = whole_lines(piece.bytes, piece.from_inside);
  const auto text = std::string_view(piece.bytes).substr(lines.from, lines.to - lines.from);
  // Offsets are the log's own: the next read goes on after the last whole line returned.
  const std::uint64_t cut = piece.bytes.size() - lines.to;
  const std::uint64_t next = piece.end - std::min(piece.end, cut);
  const std::uint64_t start = piece.start ? *piece.start + lines.from : 0;
  return op::LogsReply{file.lexically_relative(log_dir).string(), std::min(start, next), next,
                       utf8_or_replaced(text)};
}

} // namespace rsca::node
