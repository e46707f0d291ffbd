// What the loader learns from a plugin file before dlopen runs any of its code: that it is a
// readable, complete ELF shared object for this machine, and its GNU build id.
#pragma once

#include <filesystem>
#include <string>

namespace fba::detail {

struct ElfFile {
  std::string build_id;  // hex of the NT_GNU_BUILD_ID note; empty when the file has none
  std::uintmax_t size = 0;
};

// Throws std::runtime_error with the reason, worded to follow the file name: "is a directory,
// not a plugin file", "is truncated: ...", "was built for aarch64; this fba runs on x86-64".
ElfFile check_elf(const std::filesystem::path& file);

// Why a path on the plugin path is not a readable regular file ("is a dangling symbolic link to
// 'x'", "is a directory, not a plugin file"...); empty when it is one.
std::string not_a_regular_file(const std::filesystem::path& file);

}  // namespace fba::detail
