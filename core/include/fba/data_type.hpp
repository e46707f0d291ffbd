// Data types that travel on connections are named by strings ("fba.Int", "fba.Frame"), not by
// typeid: names compare the same across shared objects, compilers and hidden visibility.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace fba {

// One per registered name, owned by the core library for the life of the process, so a
// TypeInfo pointer identifies a type and pointer comparison is enough on the data path.
struct TypeInfo {
  std::string name;
  std::string doc;
};

// Registers a name (idempotent: a second registration returns the first TypeInfo).
const TypeInfo* register_type(std::string_view name, std::string_view doc);
// nullptr when the name is unknown.
const TypeInfo* find_type(std::string_view name);
std::vector<const TypeInfo*> registered_types();

// The wildcard an input declares when it accepts any type (examples.passthrough).
const TypeInfo* any_type();

template <class T>
struct DataTypeName;  // specialised by FBA_DATA_TYPE

template <class T>
const TypeInfo* type_of() {
  static const TypeInfo* const info =
      register_type(DataTypeName<T>::name, DataTypeName<T>::doc);
  return info;
}

}  // namespace fba

// Declares the wire name of a C++ type. Use at global namespace scope, in the header that
// defines the type, so every shared object agrees on it.
#define FBA_DATA_TYPE(T, NAME, DOC)                  \
  template <>                                        \
  struct fba::DataTypeName<T> {                      \
    static constexpr const char* name = NAME;        \
    static constexpr const char* doc = DOC;          \
  }
