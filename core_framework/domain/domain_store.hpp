// The domain's persistent state in SQLite: which applications are installed and which runtime
// connections an operator made, so that a domain daemon that restarts still has them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <sqlite3.h>

#include "common/diagnostic.hpp"

namespace rsca::domain {

struct InstalledRecord {
  std::string name;
  std::string sad; // path of the SAD inside the domain's repository
};

// A runtime connection (`rsca connect`) as its request: the ends, its id and QoS, as JSON.
struct ConnectionRecord {
  std::string id;
  std::string request;
};

class DomainStore {
public:
  static Expected<DomainStore> open(const std::filesystem::path &file);

  // Counts one more start of the domain daemon and returns the count: launch identities carry
  // it, so that no two runs of the daemon give out the same one.
  Expected<std::uint64_t> next_incarnation();

  Expected<void> put_installed(const InstalledRecord &record);
  Expected<void> remove_installed(const std::string &name);
  Expected<std::vector<InstalledRecord>> installed() const;
  Expected<void> put_connection(const ConnectionRecord &record);
  Expected<void> remove_connection(const std::string &id);
  Expected<std::vector<ConnectionRecord>> connections() const;

private:
  struct Closer {
    void operator()(sqlite3 *db) const { sqlite3_close(db); }
  };
  explicit DomainStore(std::unique_ptr<sqlite3, Closer> db) : db_(std::move(db)) {}
  Expected<void> exec(const std::string &sql, const std::vector<std::string> &params) const;
  // The rows of a query of two text columns.
  Expected<std::vector<std::pair<std::string, std::string>>> pairs(const char *sql,
                                                                   std::string_view what) const;
  std::unique_ptr<sqlite3, Closer> db_;
};

} // namespace rsca::domain
