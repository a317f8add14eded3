// Internal to the package cache (node/package_cache.hpp): one package laid out in a folder of its
// own, each file linked from a verified copy the cache has or fetched from the domain and
// verified. Nothing here knows the cache's index or its leases.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "node/package_cache.hpp"

namespace rsca::node::detail {

struct FetchContext {
  FetchPiece fetch;
  const CacheOptions *options = nullptr;
  std::string launch;
  // A verified copy the cache already has of the file with that hash and size.
  std::function<std::optional<std::filesystem::path>(const protocol::PackageFile &)> local_copy;
};

// Lays `package` out in `folder` (made here; the caller removes it on failure): returns the bytes
// fetched over the network.
CallResult<std::uint64_t> lay_out(const FetchContext &context, const protocol::Package &package,
                                  const std::filesystem::path &folder);

} // namespace rsca::node::detail
