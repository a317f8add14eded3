#include "node/package_fetch.hpp"

#include <cerrno>
#include <cstring>
#include <deque>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "content/sha256.hpp"
#include "content/zstd.hpp"
#include "control/operation.hpp"
#include "process/fd.hpp"
#include "profile/runtime_model.hpp"

namespace rsca::node::detail {

namespace fs = std::filesystem;
using protocol::Status;
namespace file_ops = protocol::file;

namespace {

CallResult<void> failed(Status status, std::string message) {
  return protocol::call_error(status, std::move(message));
}

CallResult<void> write_all(int fd, const protocol::Bytes &bytes, const std::string &path) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR)
      continue;
    if (n < 0)
      return failed(Status::Failed,
                    fmt::format("{}: writing it into the cache: {}", path, std::strerror(errno)));
    done += static_cast<std::size_t>(n);
  }
  return {};
}

// One file fetched piece by piece, `pieces_in_flight` of them asked for at once, written in order
// and hashed as it comes.
class FileFetch {
public:
  FileFetch(const FetchContext &context, const protocol::PackageFile &file, int fd)
      : context_(context), file_(file), fd_(fd) {}

  CallResult<void> run() {
    const auto piece = file_ops::kMaxReadBytes;
    std::uint64_t asked = 0;
    std::uint64_t written = 0;
    std::deque<std::future<CallResult<nlohmann::json>>> in_flight;
    while (written < file_.size) {
      while (asked < file_.size && in_flight.size() < context_.options->pieces_in_flight) {
        const auto length = std::min(piece, file_.size - asked);
        in_flight.push_back(context_.fetch(
            {file_.sha256, asked, length, context_.launch, std::string(file_ops::kZstd)}));
        asked += length;
      }
      auto ok = take(in_flight.front(), written);
      in_flight.pop_front();
      if (!ok)
        return drain(in_flight, ok);
    }
    const std::string got = hash_.final_hex();
    if (got != file_.sha256)
      return failed(Status::Failed,
                    fmt::format("{}: verification failed: its content hashes to {}, the package "
                                "says {}",
                                file_.path, got, file_.sha256));
    return {};
  }

private:
  // The next piece, written at `written`.
  CallResult<void> take(std::future<CallResult<nlohmann::json>> &reply, std::uint64_t &written) {
    const auto expected = std::min(file_ops::kMaxReadBytes, file_.size - written);
    if (reply.wait_for(context_.options->piece_timeout + std::chrono::seconds(1)) !=
        std::future_status::ready)
      return cut_off(written, "no reply from the domain");
    auto piece = control::reply_of<file_ops::Read>(reply.get());
    if (!piece)
      return cut_off(written, piece.error().message);
    if (piece->size != file_.size)
      return failed(Status::Failed,
                    fmt::format("{}: the domain's file has {} bytes, the package says {}",
                                file_.path, piece->size, file_.size));
    protocol::Bytes bytes = piece->payload ? std::move(*piece->payload) : protocol::Bytes{};
    if (piece->compression) {
      if (*piece->compression != file_ops::kZstd)
        return cut_off(written, fmt::format("a piece compressed as \"{}\", which the node did "
                                            "not ask for",
                                            piece->compression->substr(0, 32)));
      // Bounded by the piece asked for: a frame that holds or claims more is refused unread.
      auto plain =
          content::zstd_decompress(bytes.data(), bytes.size(), expected, file_ops::kMaxReadBytes);
      if (!plain)
        return cut_off(written, plain.error());
      bytes = protocol::Bytes(std::move(*plain));
    }
    if (bytes.size() != expected)
      return cut_off(written,
                     fmt::format("{} bytes where {} were asked for", bytes.size(), expected));
    if (auto ok = write_all(fd_, bytes, file_.path); !ok)
      return ok;
    hash_.update(bytes.data(), bytes.size());
    written += bytes.size();
    return {};
  }

  CallResult<void> cut_off(std::uint64_t written, const std::string &why) const {
    return failed(Status::Failed, fmt::format("{}: transfer cut off after {} of {} bytes: {}",
                                              file_.path, written, file_.size, why));
  }

  // The pieces still asked for end on their own (each call has its deadline); their replies are
  // not waited for.
  static CallResult<void> drain(std::deque<std::future<CallResult<nlohmann::json>>> &in_flight,
                                CallResult<void> result) {
    in_flight.clear();
    return result;
  }

  const FetchContext &context_;
  const protocol::PackageFile &file_;
  int fd_;
  content::Sha256 hash_;
};

CallResult<std::uint64_t> fetch_file(const FetchContext &context, const protocol::PackageFile &file,
                                     const fs::path &target) {
  process::Fd fd(::open(target.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0600));
  if (!fd)
    return protocol::call_error(Status::Failed, fmt::format("{}: cannot create it in the cache: {}",
                                                            file.path, std::strerror(errno)));
  if (auto ok = FileFetch(context, file, fd.get()).run(); !ok)
    return tl::unexpected(ok.error());
  if (::fsync(fd.get()) != 0)
    return protocol::call_error(Status::Failed, fmt::format("{}: writing it into the cache: {}",
                                                            file.path, std::strerror(errno)));
  return file.size;
}

// A copy the cache has, linked when it still is what it was verified as (its size; its content is
// read-only) and has the mode this package gives it: a link shares its file's mode.
bool link_copy(const FetchContext &context, const protocol::PackageFile &file,
               const fs::path &target) {
  if (!context.local_copy)
    return false;
  auto copy = context.local_copy(file);
  if (!copy)
    return false;
  std::error_code ec;
  if (fs::file_size(*copy, ec) != file.size || ec)
    return false;
  const bool executable =
      (fs::status(*copy, ec).permissions() & fs::perms::owner_exec) != fs::perms::none;
  if (ec || executable != file.executable)
    return false;
  fs::create_hard_link(*copy, target, ec);
  return !ec;
}

CallResult<std::uint64_t> place(const FetchContext &context, const protocol::PackageFile &file,
                                const fs::path &folder) {
  const fs::path target = folder / file.path;
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  if (ec)
    return protocol::call_error(
        Status::Failed, fmt::format("{}: cannot make its folder: {}", file.path, ec.message()));
  if (link_copy(context, file, target))
    return 0;
  auto fetched = fetch_file(context, file, target);
  if (!fetched)
    return fetched;
  fs::permissions(target, file.executable ? fs::perms(0555) : fs::perms(0444),
                  fs::perm_options::replace, ec);
  if (ec)
    return protocol::call_error(Status::Failed, fmt::format("{}: {}", file.path, ec.message()));
  return fetched;
}

} // namespace

CallResult<std::uint64_t> lay_out(const FetchContext &context, const protocol::Package &package,
                                  const fs::path &folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec)
    return protocol::call_error(Status::Failed,
                                fmt::format("cannot make {}: {}", folder.string(), ec.message()));
  std::uint64_t fetched = 0;
  for (const auto &file : package.files) {
    auto placed = place(context, file, folder);
    if (!placed)
      return placed;
    fetched += *placed;
  }
  // The models name their sources as the domain has them: now as this package has them.
  for (const auto &file : package.files)
    if (profile::is_runtime_model_path(file.path))
      if (auto ok = profile::relocate_runtime_model(folder, file.path, package.origin); !ok)
        spdlog::warn("package {}: {}; its component reads its XML instead",
                     folder.filename().string(), ok.error().to_string());
  // Its folders read-only too: a process runs inside its package, and must not change what
  // other packages link to.
  for (auto it = fs::recursive_directory_iterator(folder, ec); !ec && it != fs::end(it);
       it.increment(ec))
    if (it->is_directory(ec))
      fs::permissions(it->path(), fs::perms(0555), fs::perm_options::replace, ec);
  fs::permissions(folder, fs::perms(0555), fs::perm_options::replace, ec);
  return fetched;
}

} // namespace rsca::node::detail
