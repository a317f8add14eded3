#include "domain/domain_store.hpp"

#include <fmt/format.h>

namespace rsca::domain {
namespace {

struct StatementDeleter {
  void operator()(sqlite3_stmt *s) const { sqlite3_finalize(s); }
};
using Statement = std::unique_ptr<sqlite3_stmt, StatementDeleter>;

tl::unexpected<Error> sqlite_error(sqlite3 *db, std::string_view what) {
  return make_error({"domain store", 0, 0}, "store",
                    fmt::format("{}: {}", what, sqlite3_errmsg(db)));
}

} // namespace

Expected<DomainStore> DomainStore::open(const std::filesystem::path &file) {
  sqlite3 *raw = nullptr;
  const int rc = sqlite3_open(file.c_str(), &raw);
  std::unique_ptr<sqlite3, Closer> db(raw);
  if (rc != SQLITE_OK)
    return sqlite_error(db.get(), fmt::format("opening {}", file.string()));
  DomainStore store(std::move(db));
  for (const char *table : {"CREATE TABLE IF NOT EXISTS installed ("
                            " name TEXT PRIMARY KEY, sad TEXT NOT NULL,"
                            " installed_at TEXT NOT NULL DEFAULT CURRENT_TIMESTAMP)",
                            "CREATE TABLE IF NOT EXISTS runtime_connections ("
                            " id TEXT PRIMARY KEY, request TEXT NOT NULL,"
                            " made_at TEXT NOT NULL DEFAULT CURRENT_TIMESTAMP)",
                            "CREATE TABLE IF NOT EXISTS counters ("
                            " name TEXT PRIMARY KEY, value INTEGER NOT NULL)"})
    if (auto ok = store.exec(table, {}); !ok)
      return tl::unexpected(ok.error());
  return store;
}

Expected<void> DomainStore::exec(const std::string &sql,
                                 const std::vector<std::string> &params) const {
  sqlite3_stmt *raw = nullptr;
  if (sqlite3_prepare_v2(db_.get(), sql.c_str(), -1, &raw, nullptr) != SQLITE_OK)
    return sqlite_error(db_.get(), "preparing a statement");
  Statement statement(raw);
  for (std::size_t i = 0; i < params.size(); ++i)
    sqlite3_bind_text(raw, static_cast<int>(i + 1), params[i].c_str(), -1, SQLITE_TRANSIENT);
  if (sqlite3_step(raw) != SQLITE_DONE)
    return sqlite_error(db_.get(), "writing");
  return {};
}

Expected<std::uint64_t> DomainStore::next_incarnation() {
  if (auto counted = exec("INSERT INTO counters (name, value) VALUES ('incarnation', 1)"
                          " ON CONFLICT (name) DO UPDATE SET value = value + 1",
                          {});
      !counted)
    return tl::unexpected(counted.error());
  sqlite3_stmt *raw = nullptr;
  if (sqlite3_prepare_v2(db_.get(), "SELECT value FROM counters WHERE name = 'incarnation'", -1,
                         &raw, nullptr) != SQLITE_OK)
    return sqlite_error(db_.get(), "reading the incarnation");
  Statement statement(raw);
  if (sqlite3_step(raw) != SQLITE_ROW)
    return sqlite_error(db_.get(), "reading the incarnation");
  return static_cast<std::uint64_t>(sqlite3_column_int64(raw, 0));
}

Expected<void> DomainStore::put_installed(const InstalledRecord &record) {
  return exec("INSERT OR REPLACE INTO installed (name, sad) VALUES (?, ?)",
              {record.name, record.sad});
}

Expected<void> DomainStore::remove_installed(const std::string &name) {
  return exec("DELETE FROM installed WHERE name = ?", {name});
}

Expected<std::vector<std::pair<std::string, std::string>>>
DomainStore::pairs(const char *sql, std::string_view what) const {
  sqlite3_stmt *raw = nullptr;
  if (sqlite3_prepare_v2(db_.get(), sql, -1, &raw, nullptr) != SQLITE_OK)
    return sqlite_error(db_.get(), fmt::format("reading {}", what));
  Statement statement(raw);
  std::vector<std::pair<std::string, std::string>> rows;
  while (sqlite3_step(raw) == SQLITE_ROW)
    rows.emplace_back(reinterpret_cast<const char *>(sqlite3_column_text(raw, 0)),
                      reinterpret_cast<const char *>(sqlite3_column_text(raw, 1)));
  return rows;
}

Expected<std::vector<InstalledRecord>> DomainStore::installed() const {
  auto rows = pairs("SELECT name, sad FROM installed ORDER BY name", "installed applications");
  if (!rows)
    return tl::unexpected(rows.error());
  std::vector<InstalledRecord> records;
  for (auto &[name, sad] : *rows)
    records.push_back({std::move(name), std::move(sad)});
  return records;
}

Expected<void> DomainStore::put_connection(const ConnectionRecord &record) {
  return exec("INSERT OR REPLACE INTO runtime_connections (id, request) VALUES (?, ?)",
              {record.id, record.request});
}

Expected<void> DomainStore::remove_connection(const std::string &id) {
  return exec("DELETE FROM runtime_connections WHERE id = ?", {id});
}

Expected<std::vector<ConnectionRecord>> DomainStore::connections() const {
  auto rows = pairs("SELECT id, request FROM runtime_connections ORDER BY made_at, id",
                    "runtime connections");
  if (!rows)
    return tl::unexpected(rows.error());
  std::vector<ConnectionRecord> records;
  for (auto &[id, request] : *rows)
    records.push_back({std::move(id), std::move(request)});
  return records;
}

} // namespace rsca::domain
