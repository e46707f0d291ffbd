// Data types that travel on connections are named by strings ("fba.Int", "fba.Frame"), not by
// typeid: names compare the same across shared objects, compilers and hidden visibility.
// Each name carries a layout fingerprint (size, alignment, and a version the type's author bumps
// when the layout or meaning changes), so two plugins built against different definitions of one
// name are refused instead of exchanging objects that crash.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace fba {

struct TypeLayout {
  std::size_t size = 0;  // 0: not known (a name registered without its C++ type, e.g. "any")
  std::size_t align = 0;
  unsigned version = 0;
  bool known() const { return size != 0; }
  bool operator==(const TypeLayout&) const = default;
};
// "size 48, alignment 8, version 1", or "unknown layout".
std::string to_string(const TypeLayout& layout);

// One per registered name, owned by the core library for the life of the process, so a
// TypeInfo pointer identifies a type and pointer comparison is enough on the data path.
struct TypeInfo {
  std::string name;
  std::string doc;
  TypeLayout layout;
  std::string header;  // the header that declares it ("fba/types/octree.hpp"), when known
  std::string origin;  // who registered the layout first: a plugin file, or "" for the program itself
};

// Registers a name (idempotent: a second registration returns the first TypeInfo). A known layout
// that differs from the one registered first throws std::logic_error naming both layouts and
// both origins.
const TypeInfo* register_type(std::string_view name, std::string_view doc, TypeLayout layout = {},
                              std::string_view header = {});
// nullptr when the name is unknown.
const TypeInfo* find_type(std::string_view name);
std::vector<const TypeInfo*> registered_types();

// The wildcard an input declares when it accepts any type (examples.passthrough).
const TypeInfo* any_type();

// While alive, layouts registered on this thread are attributed to `origin` (a plugin file):
// the registry sets it while it reads a plugin's component specs.
class TypeOriginScope {
 public:
  explicit TypeOriginScope(std::string origin);
  ~TypeOriginScope();
  TypeOriginScope(const TypeOriginScope&) = delete;
  TypeOriginScope& operator=(const TypeOriginScope&) = delete;

 private:
  std::string previous_;
};

template <class T>
struct DataTypeName;  // specialised by FBA_DATA_TYPE

namespace detail {
constexpr unsigned data_type_version(unsigned v = 1) { return v; }
// "…/include/fba/types/octree.hpp" -> "fba/types/octree.hpp": the name a user includes.
std::string_view include_name(std::string_view file);
}  // namespace detail

template <class T>
const TypeInfo* type_of() {
  static const TypeInfo* const info =
      register_type(DataTypeName<T>::name, DataTypeName<T>::doc,
                    TypeLayout{sizeof(T), alignof(T), DataTypeName<T>::version}, detail::include_name(DataTypeName<T>::header));
  return info;
}

}  // namespace fba

// Declares the wire name of a C++ type. Use at global namespace scope, in the header that
// defines the type, so every shared object agrees on it. An optional fourth argument is the
// type's layout version (default 1): bump it when the layout or meaning changes without
// changing the size, so plugins built against the old definition are refused.
#define FBA_DATA_TYPE(T, NAME, DOC, ...)                                                   \
  template <>                                                                              \
  struct fba::DataTypeName<T> {                                                            \
    static constexpr const char* name = NAME;                                              \
    static constexpr const char* doc = DOC;                                                \
    static constexpr unsigned version = ::fba::detail::data_type_version(__VA_ARGS__);     \
    static constexpr const char* header = __FILE__;                                        \
  }
