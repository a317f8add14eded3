#include "domain/application_registry.hpp"

#include <fmt/format.h>

namespace rsca::domain {

using control::Status;

control::CallResult<std::string> ApplicationRegistry::reserve(const std::string &wanted, bool exact,
                                                              const std::string &installed) {
  std::lock_guard lock(mutex_);
  std::string name = wanted;
  if (exact && taken(name))
    return control::call_error(Status::Rejected,
                               fmt::format("an application named {} already runs", wanted));
  for (int i = 2; taken(name); ++i)
    name = fmt::format("{}_{}", wanted, i);
  entries_[name] = Entry{installed, {}};
  return name;
}

void ApplicationRegistry::drop(const std::string &name) {
  std::lock_guard lock(mutex_);
  if (auto it = entries_.find(name); it != entries_.end() && !it->second.handle.app)
    entries_.erase(it);
}

void ApplicationRegistry::commit(std::shared_ptr<Application> app) {
  std::lock_guard lock(mutex_);
  auto &entry = entries_[app->name];
  entry.installed = app->installed;
  entry.handle = Handle{std::move(app), std::make_shared<std::mutex>()};
}

bool ApplicationRegistry::launching(const std::string &installed) const {
  std::lock_guard lock(mutex_);
  for (const auto &[name, entry] : entries_)
    if (!entry.handle.app && entry.installed == installed)
      return true;
  return false;
}

control::CallResult<ApplicationRegistry::Handle>
ApplicationRegistry::find(const std::string &name) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  if (it == entries_.end() || !it->second.handle.app)
    return control::call_error(Status::NotFound, fmt::format("no application {} is running", name));
  return it->second.handle;
}

std::optional<ApplicationRegistry::Handle> ApplicationRegistry::remove(const std::string &name) {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  if (it == entries_.end() || !it->second.handle.app)
    return std::nullopt;
  Handle handle = std::move(it->second.handle);
  entries_.erase(it);
  return handle;
}

bool ApplicationRegistry::update(const std::string &name,
                                 const std::function<void(Application &)> &change) {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  if (it == entries_.end() || !it->second.handle.app)
    return false;
  change(*it->second.handle.app);
  return true;
}

void ApplicationRegistry::update_all(const std::function<void(Application &)> &change) {
  std::lock_guard lock(mutex_);
  for (auto &[name, entry] : entries_)
    if (entry.handle.app)
      change(*entry.handle.app);
}

std::optional<Application> ApplicationRegistry::snapshot(const std::string &name) const {
  std::lock_guard lock(mutex_);
  auto it = entries_.find(name);
  if (it == entries_.end() || !it->second.handle.app)
    return std::nullopt;
  return *it->second.handle.app;
}

std::vector<Application> ApplicationRegistry::snapshots() const {
  std::lock_guard lock(mutex_);
  std::vector<Application> out;
  for (const auto &[name, entry] : entries_)
    if (entry.handle.app)
      out.push_back(*entry.handle.app);
  return out;
}

std::vector<std::string> ApplicationRegistry::running_from(const std::string &installed) const {
  std::lock_guard lock(mutex_);
  std::vector<std::string> names;
  for (const auto &[name, entry] : entries_)
    if (entry.handle.app && entry.installed == installed)
      names.push_back(name);
  return names;
}

} // namespace rsca::domain
