#include "fba/data_type.hpp"

#include <map>
#include <memory>
#include <mutex>

namespace fba {
namespace {

struct TypeTable {
  std::mutex mutex;
  std::map<std::string, std::unique_ptr<TypeInfo>, std::less<>> by_name;
};

TypeTable& table() {
  static TypeTable* t = new TypeTable;  // never destroyed: TypeInfo pointers outlive everything
  return *t;
}

}  // namespace

const TypeInfo* register_type(std::string_view name, std::string_view doc) {
  auto& t = table();
  std::lock_guard lock(t.mutex);
  auto it = t.by_name.find(name);
  if (it != t.by_name.end()) {
    if (it->second->doc.empty()) it->second->doc = doc;
    return it->second.get();
  }
  auto info = std::make_unique<TypeInfo>(TypeInfo{std::string(name), std::string(doc)});
  const TypeInfo* p = info.get();
  t.by_name.emplace(std::string(name), std::move(info));
  return p;
}

const TypeInfo* find_type(std::string_view name) {
  auto& t = table();
  std::lock_guard lock(t.mutex);
  auto it = t.by_name.find(name);
  return it == t.by_name.end() ? nullptr : it->second.get();
}

std::vector<const TypeInfo*> registered_types() {
  auto& t = table();
  std::lock_guard lock(t.mutex);
  std::vector<const TypeInfo*> out;
  for (auto& [_, info] : t.by_name) out.push_back(info.get());
  return out;
}

const TypeInfo* any_type() {
  static const TypeInfo* const any = register_type("any", "Any type; the checker resolves it from the connection.");
  return any;
}

}  // namespace fba
