#include "fba/data_type.hpp"

#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>

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

thread_local std::string current_origin;

std::string origin_name(const std::string& origin) { return origin.empty() ? "the program (fba and its libraries)" : origin; }

}  // namespace

std::string to_string(const TypeLayout& l) {
  if (!l.known()) return "unknown layout";
  return "size " + std::to_string(l.size) + ", alignment " + std::to_string(l.align) + ", version " + std::to_string(l.version);
}

TypeOriginScope::TypeOriginScope(std::string origin) : previous_(std::move(current_origin)) { current_origin = std::move(origin); }
TypeOriginScope::~TypeOriginScope() { current_origin = std::move(previous_); }

const TypeInfo* register_type(std::string_view name, std::string_view doc, TypeLayout layout, std::string_view header) {
  auto& t = table();
  std::lock_guard lock(t.mutex);
  auto it = t.by_name.find(name);
  if (it != t.by_name.end()) {
    TypeInfo& info = *it->second;
    if (info.doc.empty()) info.doc = doc;
    if (info.header.empty()) info.header = header;
    if (layout.known()) {
      if (!info.layout.known()) {
        info.layout = layout;
        info.origin = current_origin;
      } else if (info.layout != layout) {
        throw std::logic_error("data type '" + info.name + "' has two layouts: " + to_string(info.layout) + " in " +
                               origin_name(info.origin) + ", and " + to_string(layout) + " in " + origin_name(current_origin) +
                               ": rebuild them against the same definition of the type");
      }
    }
    return &info;
  }
  auto info = std::make_unique<TypeInfo>(TypeInfo{std::string(name), std::string(doc), layout, std::string(header),
                                                  layout.known() ? current_origin : std::string()});
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

namespace detail {
std::string_view include_name(std::string_view file) {
  const auto at = file.rfind("/include/");
  if (at != std::string_view::npos) return file.substr(at + 9);
  const auto slash = file.rfind('/');
  return slash == std::string_view::npos ? file : file.substr(slash + 1);
}
}  // namespace detail

}  // namespace fba
