// The plugin ABI: what a plugin shared object exports, checked before anything else is used.
// Plugin authors do not include this: fba_add_plugin() generates the entry point.
#pragma once

#include <cstdint>
#include <vector>

#include "fba/component.hpp"
#include "fba/version.hpp"

namespace fba {

// Bumped whenever a header a plugin compiles against changes layout or meaning.
inline constexpr std::uint32_t kAbiVersion = 3;  // 3: Spec::concurrent_safe_state (Spec's layout)
inline constexpr std::uint32_t kPluginMagic = 0x46424131;  // "FBA1"

// The C++ library ABI the plugin was built against: a plugin built with another standard
// library or dual-ABI setting would crash on the first std::string that crosses over.
#if defined(_GLIBCXX_USE_CXX11_ABI)
#define FBA_BUILD_ABI_TAG "libstdc++ cxx11-abi=" FBA_STRINGIFY(_GLIBCXX_USE_CXX11_ABI)
#elif defined(_LIBCPP_VERSION)
#define FBA_BUILD_ABI_TAG "libc++"
#else
#define FBA_BUILD_ABI_TAG "unknown"
#endif
#define FBA_STRINGIFY_INNER(x) #x
#define FBA_STRINGIFY(x) FBA_STRINGIFY_INNER(x)

struct PluginInfo {
  std::uint32_t magic;
  std::uint32_t abi_version;
  const char* name;
  const char* fba_version;
  const char* build_abi;
};

// Symbol names looked up in every plugin.
inline constexpr const char* kPluginInfoSymbol = "fba_plugin_info";
inline constexpr const char* kPluginComponentsSymbol = "fba_plugin_components";
using PluginComponentsFn = const std::vector<detail::ComponentEntry>* (*)();

}  // namespace fba

// Defines a plugin's entry points; fba_add_plugin() writes this line into a generated source.
#define FBA_PLUGIN(NAME)                                                                       \
  extern "C" [[gnu::visibility("default")]] const ::fba::PluginInfo fba_plugin_info = {       \
      ::fba::kPluginMagic, ::fba::kAbiVersion, NAME, FBA_VERSION, FBA_BUILD_ABI_TAG};          \
  extern "C" [[gnu::visibility("default")]] const std::vector<::fba::detail::ComponentEntry>* \
  fba_plugin_components() {                                                                    \
    return &::fba::detail::plugin_entries();                                                   \
  }
