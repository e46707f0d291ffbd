// Guarded YAML reading, the loader's first stage: a task, composite or profile file read as text
// only when it is a regular file of at most 4 MiB; the text parsed as one YAML document after the
// guards that keep yaml-cpp 0.7 from looping for ever or recursing without bound on malformed text
// (the fuzzer found each shape); then every mapping checked for duplicate keys and merge keys,
// which yaml-cpp accepts silently. Apart from the later stages because none of this is about
// tasks: it decides whether there is a YAML document to read at all, and says where there is not.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "fba/task_config.hpp"

namespace fba::loader {

namespace fs = std::filesystem;

struct Source {
  std::string shown;     // file name as the user gave it
  fs::path dir;          // relative paths resolve here
  bool has_lines = true; // false for --set values: the place is the option itself
  const char* base = "the task file";  // what relative paths are relative to, for messages
};

// Where node `n` was written in `src` (the place of the option itself when it has no lines).
Location at(const Source& src, const YAML::Node& n);

// How messages name a node's kind: "nothing", "a scalar", "a list", "a mapping".
const char* node_kind(const YAML::Node& n);

// Task and composite files are read whole, so anything that is not a file of a sensible size is
// refused before reading: /dev/zero or a FIFO would never end, a huge file would exhaust memory.
constexpr std::uintmax_t kMaxFileBytes = 4u << 20;

// The text of a task or composite file; on failure `problem` says why, as in "'x' PROBLEM".
std::string read_text(const fs::path& path, std::string& problem);

// One YAML document, or nothing with the reasons added to `d`. A second document would be
// ignored by a plain load, and its content silently lost.
std::optional<YAML::Node> parse_yaml(const std::string& text, const std::string& shown, std::vector<Diagnostic>& d);

// yaml-cpp keeps every duplicate key of a mapping (a lookup finds the first) and reads the merge
// key '<<' as an ordinary key: both would silently change what a file means, so both are errors.
// A node reached again through an alias is walked once (aliases can multiply a tree exponentially).
void check_mappings(const YAML::Node& root, const Source& src, std::vector<Diagnostic>& d);

}  // namespace fba::loader
