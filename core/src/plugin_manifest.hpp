// A plugin's manifest: what the plugin offers, written at build time beside "fba-<name>.so" as
// "fba-<name>.manifest.json" by fba-plugin-manifest, so the registry lists and checks a plugin
// without running any of its code.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "fba/data_type.hpp"
#include "fba/spec.hpp"

namespace fba::detail {

inline constexpr int kManifestFormat = 1;

struct ManifestType {
  std::string name;
  std::string kind;       // "sensor", "filter", "actuator"
  std::string interface;  // JSON text: the form spec_json() writes
};

struct ManifestDataType {
  std::string name, doc, header;
  TypeLayout layout;
};

struct Manifest {
  // The ABI record, as the plugin's fba_plugin_info holds it.
  std::uint32_t magic = 0;
  std::uint32_t abi_version = 0;
  std::string fba_version, build_abi, name;
  std::string build_id;  // of the .so it describes
  std::vector<ManifestType> types;
  std::vector<ManifestDataType> data_types;  // every data type its ports use, with its layout
};

// "…/fba-x.so" -> "…/fba-x.manifest.json".
std::filesystem::path manifest_path(const std::filesystem::path& plugin);

// Throws std::runtime_error saying what is wrong and where in the file.
Manifest read_manifest(const std::filesystem::path& file);
std::string manifest_json(const Manifest& m);

// A component type's interface as JSON text (kind, ports with types, params with type, default,
// range, choices and doc, events, stages, trigger, blocking): manifests and fba-inspect --json.
std::string spec_json(const Spec& spec);
// The data types a spec's ports use, with their layouts.
std::vector<ManifestDataType> data_types_of(const Spec& spec);

}  // namespace fba::detail

namespace fba::detail {
// Loads a plugin (running its code) and describes it: what fba-plugin-manifest writes at build
// time. Throws std::runtime_error with the reason.
Manifest describe_plugin(const std::filesystem::path& file);
}  // namespace fba::detail
